"""The forward model: what the robot expects its behaviours to do (thesis 8.6).

For an object f, a behaviour b and its parameters alpha, the predictor gives P(E | f, b,
alpha) over b's effect categories; the next state of that object is f plus the effect
category E has on f, and no other object changes (chapter 8). That effect is, by default,
the mean effect of the members of E whose entities looked most like f
(:class:`afford.learn.members.MemberEffects`), and a sampled rollout draws one of those
members' effects; ``effects="prototype"`` gives the thesis's model, f + prototype(E), for
every member alike (models trained before member effects existed have only that). Where the model also learned P(known | f, b, alpha),
the chance that the effect is of a kind its categories kept at all, the category
probabilities are multiplied by it: the rest is an unknown outcome, which no plan counts on
(an imagined world, :func:`afford.plan.monitor.reach_probability`, draws it from what the
discarded members most like f did: :meth:`ForwardModel.draw_unknown`). An object that the prototype makes vanish keeps its
last seen position and shape with visibility 0, as perception does.

Predictions depend only on the object's own features, so they are cached by the object's
feature bytes: a search meets the same object vector in many states.
"""

from __future__ import annotations

import functools
import threading
from dataclasses import dataclass, field
from itertools import product

import numpy as np

from afford.features import encode_parameters
from afford.features.errors import DataError

__all__ = ["BehaviorModel", "ForwardModel", "Outcome", "SCENE", "EFFECT_MODELS", "ALPHA_RULES"]

#: How the planner picks a behaviour's parameter (``ForwardModel(alpha_rule=...)``).
ALPHA_RULES = ("grid", "group", "probability")

#: How a category's effect on one entity is predicted (``ForwardModel(effects=...)``).
EFFECT_MODELS = ("members", "prototype")


#: The object index a step on a behaviour without a target carries: it acts on the scene.
SCENE = -1

@functools.cache
def _blas():
    from threadpoolctl import ThreadpoolController

    return ThreadpoolController()


#: Whether this thread runs inside :func:`one_blas_thread` (nested calls skip the limit).
_one_thread = threading.local()


def one_blas_thread(fn):
    """Run ``fn`` with the BLAS libraries on one thread. Planning makes tens of thousands of
    small products (a few vectors against a classifier's support vectors or a category's
    members); a second BLAS thread only adds hand-over latency to each, and when the cores
    are busy it waits for one: on the table's planning benchmark (4 scenes, member effects),
    with both cores busy exploring, assessing the plans took 48.9 s on two BLAS threads and
    31.4 s on one; on an idle machine the two are alike (17-19 s, within the noise). The
    limit costs about 10 microseconds (nothing inside another); it wraps the searches,
    execution, the imagined rollouts, ``prefetch`` (where ``predict`` and ``evaluate``
    enter) and the alpha choices a prefetch owes (made when first needed)."""
    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        if getattr(_one_thread, "on", False):  # already limited by a caller
            return fn(*args, **kwargs)
        with _blas().limit(limits=1, user_api="blas"):
            _one_thread.on = True
            try:
                return fn(*args, **kwargs)
            finally:
                _one_thread.on = False

    return wrapper


@dataclass
class BehaviorModel:
    """What the planner needs of one learned behaviour."""

    name: str
    predictor: object                  # predict_proba, classes_
    selected: np.ndarray               # entity-feature columns the predictor reads
    prototypes: np.ndarray | None      # (n_categories, d) mean effects; None: labels given, no effects
    parameters: list[tuple[float, float]] = field(default_factory=list)  # alpha ranges
    known: object | None = None        # P(the effect is of a kept kind): predict_proba, classes_ [0, 1]
    known_selected: np.ndarray | None = None  # the columns ``known`` reads (None: ``selected``)
    periodic: tuple[bool, ...] = ()    # which parameters are angles (encoded as sine and cosine)
    target: str | None = "object"      # None: the behaviour acts on no one object; every row may change
    members: object | None = None      # MemberEffects: each entity's own effect within a category


@dataclass(frozen=True)
class Outcome:
    category: int | tuple
    probability: float
    state: np.ndarray


def _as_slice(index: np.ndarray):
    """``index`` as a slice when it is a run of consecutive integers, else unchanged."""
    if isinstance(index, slice):
        return index
    if index.ndim == 1 and index.size and index.dtype.kind in "iu" and np.array_equal(index, np.arange(index[0], index[0] + index.size)):
        return slice(int(index[0]), int(index[0]) + index.size)
    return index


def _largest_run(mask: np.ndarray, circle: bool) -> np.ndarray:
    """Indices of the longest run of True in ``mask`` (wrapping round if ``circle``); the
    first of equally long ones."""
    n = mask.size
    if mask.all():
        return np.arange(n)
    start = int(np.argmin(mask)) if circle else 0  # begin on a False so no run is cut in two
    order = (np.arange(n) + start) % n if circle else np.arange(n)
    best, run = [], []
    for i in order:
        if mask[i]:
            run.append(int(i))
            if len(run) > len(best):
                best = list(run)
        else:
            run = []
    return np.asarray(best, dtype=int)


def _mean_angle(degrees: np.ndarray) -> float:
    """The circular mean of angles in degrees (-180..180)."""
    r = np.radians(np.asarray(degrees, dtype=float))
    return float(np.degrees(np.arctan2(np.sin(r).mean(), np.cos(r).mean())))


class ForwardModel:
    """P(next state | state, behaviour, object, alpha) from learned predictors and prototypes.

    Parameters
    ----------
    behaviors : list of BehaviorModel
    schema : FeatureSchema
        What the entity features mean: the visibility feature (none: always visible), the
        histograms (after adding a prototype they are clipped at 0 and renormalised, so a
        predicted entity stays one the predictors could have seen) and the ``height`` role
        (with it the planner knows when a step leaves an object in the hand,
        :meth:`in_hand`).
    min_probability : float
        Outcomes less likely than this are not expanded by the search.
    param_steps : int
        Grid points per parameter of a parametric behaviour (chapter 9).
    raised : float
        Rise (metres) of the height feature that means an object is held.
    height : int or None
        Overrides the schema's ``height`` role.
    effects : {"members", "prototype"}
        How a category's effect on an entity is predicted: from the category's members most
        like it (where the model has them), or the category's prototype for all (the thesis).
    alpha_rule : {"grid", "group", "probability"}
        Which parameters the planner tries for a behaviour of one parameter (chapter 9):
        ``grid``, every point of a ``param_steps`` grid; ``group``, thesis 9.5: over an
        ``alpha_grid``-point grid, the alphas that lead to the same predicted next state
        (the same most probable category) are grouped, and for each next state the mean
        of its largest group (a run of neighbouring grid points; circular for an angle) is
        tried; ``probability`` (our extension): for each predicted next state, the grid
        point that makes it most probable. Behaviours of several parameters use the grid.
    alpha_grid : int
        Grid points the ``group`` and ``probability`` rules search.

    A behaviour whose ``target`` is None acts on the whole scene: every visible row changes
    by its own predicted effect, and an outcome is one category per row (its probability
    the product of theirs, rows taken as independent given their features).
    """

    def __init__(self, behaviors: list[BehaviorModel], schema, min_probability: float = 0.02,
                 param_steps: int = 5, raised: float = 0.05, height: int | None = None,
                 effects: str = "members", alpha_rule: str = "grid", alpha_grid: int = 36):
        if effects not in EFFECT_MODELS:
            raise DataError(f"unknown effect model {effects!r}; choose {' or '.join(EFFECT_MODELS)}")
        if alpha_rule not in ALPHA_RULES:
            raise DataError(f"unknown alpha rule {alpha_rule!r}; choose {', '.join(ALPHA_RULES)}")
        self.alpha_rule = alpha_rule
        self.alpha_grid = int(alpha_grid)
        self._choices: dict[tuple, list] = {}
        # (behaviour, vector bytes) -> vector whose alpha choices a prefetch owes, made when
        # first needed (:meth:`_settle`)
        self._owed: dict[tuple[int, bytes], np.ndarray] = {}
        self._columns: dict[tuple[int, tuple], tuple[BehaviorModel, np.ndarray]] = {}
        self._rows: dict[tuple[int, tuple], tuple[BehaviorModel, np.ndarray]] = {}
        self._grids: dict[tuple[int, int], tuple] = {}
        self.behaviors = behaviors
        self.effects = effects
        self.schema = schema
        self.visibility = schema.visibility_index
        self.height = height if height is not None else schema.role("height")
        self.raised = raised
        self.histograms = [_as_slice(h) for h in schema.histogram_slices]
        self.names = [b.name for b in behaviors]
        self.min_probability = min_probability
        self.param_steps = param_steps
        self._cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._effect_cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._fast: dict[int, object] = {}
        self.predictions = 0

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise DataError(f"unknown behaviour {name!r}; the model knows {', '.join(self.names)}") from None

    @property
    def predicts_effects(self) -> bool:
        """Do all behaviours have effect prototypes (labels discovered, not given)?"""
        return all(b.prototypes is not None for b in self.behaviors)

    def visible(self, f: np.ndarray) -> bool:
        """Is the entity (row) seen? Always, for a schema without a visibility feature."""
        return self.visibility is None or bool(f[self.visibility] >= 0.5)

    def alphas(self, b: int) -> list[tuple[float, ...]]:
        """The parameter grid of behaviour ``b`` (one empty tuple for a behaviour without)."""
        ranges = self.behaviors[b].parameters
        if not ranges:
            return [()]
        axes = [np.linspace(lo, hi, self.param_steps) for lo, hi in ranges]
        return [tuple(float(v) for v in p) for p in product(*axes)]

    def _chooses(self, b: int) -> bool:
        """Does behaviour ``b`` choose its parameter by a rule rather than try a grid?"""
        return self.alpha_rule != "grid" and len(self.behaviors[b].parameters) == 1

    def choice_grid(self, b: int) -> np.ndarray:
        """The ``alpha_grid`` points a rule searches for behaviour ``b``'s one parameter
        (a full circle's end point left out: it is its start)."""
        lo, hi = self.behaviors[b].parameters[0]
        model = self.behaviors[b]
        circle = bool(model.periodic[0]) if len(model.periodic) else False
        circle = circle and abs((hi - lo) - 360.0) < 1e-9
        return np.linspace(lo, hi, self.alpha_grid, endpoint=not circle)

    def _grid(self, b: int) -> tuple[np.ndarray, tuple[tuple[float], ...]]:
        """:meth:`choice_grid` and its points as parameter tuples, once per behaviour."""
        key = (b, self.alpha_grid)
        hit = self._grids.get(key)
        if hit is None:
            grid = self.choice_grid(b)
            hit = self._grids[key] = (grid, tuple((float(a),) for a in grid))
        return hit

    def choose_alphas(self, f: np.ndarray, b: int, rule: str | None = None) -> list[tuple[tuple[float, ...], int]]:
        """(alpha, the next state's category) for each next state behaviour ``b`` can bring
        entity ``f`` to, by ``rule`` (default: the model's ``alpha_rule``; see the class
        docstring). One batch of predictions over the grid."""
        rule = rule or self.alpha_rule
        if rule not in ("group", "probability"):
            raise DataError(f"choose_alphas needs the group or the probability rule, not {rule!r}")
        key = (b, f.tobytes(), rule)
        if self._owed:
            self._settle(b, key[1])
        hit = self._choices.get(key)
        if hit is not None:
            return hit
        model = self.behaviors[b]
        grid, alphas = self._grid(b)
        classes, proba = self._predict_alphas(f, b, alphas)
        best = np.argmax(proba, axis=1)
        periodic = bool(model.periodic[0]) if len(model.periodic) else False
        circle = periodic and abs((model.parameters[0][1] - model.parameters[0][0]) - 360.0) < 1e-9
        out = []
        for j in dict.fromkeys(best.tolist()):
            if rule == "probability":
                alpha = float(grid[int(np.argmax(proba[:, j]))])
            else:
                run = _largest_run(best == j, circle)
                alpha = _mean_angle(grid[run]) if periodic else float(grid[run].mean())
            if circle:
                lo = model.parameters[0][0]
                alpha = lo + (alpha - lo) % 360.0
            out.append(((round(alpha, 6),), int(classes[j])))
        self._choices[key] = out
        return out

    def alpha_choices(self, f: np.ndarray, b: int) -> list[tuple[float, ...]]:
        """The parameters the planner tries for behaviour ``b`` on entity ``f``."""
        if not self._chooses(b):
            return self.alphas(b)
        return [a for a, _ in self.choose_alphas(f, b)]

    def _predict_alphas(self, f: np.ndarray, b: int, alphas: list[tuple]) -> tuple[np.ndarray, np.ndarray]:
        """(categories, P per alpha and category) for entity ``f`` under each of ``alphas``, in
        one batch; the results are cached as :meth:`distribution` keeps them."""
        model = self.behaviors[b]
        A = self._alpha_rows(model, tuple(alphas))

        def rows(selected):  # the entity's columns beside each alpha's (the same numbers as one row at a time)
            return np.concatenate([np.broadcast_to(f[selected], (len(alphas), len(selected))), A], axis=1)

        X = rows(model.selected)
        proba = self._proba(model.predictor)(X)
        if model.known is not None:
            Xk = X if model.known_selected is None else rows(model.known_selected)
            proba = proba * self._proba(model.known)(Xk)[:, list(model.known.classes_).index(1)][:, None]
        classes = np.asarray(model.predictor.classes_, dtype=int)
        key = f.tobytes()
        for a, p in zip(alphas, proba):
            self._cache[(b, key, a)] = (classes, p)
        self.predictions += len(alphas)
        return classes, proba

    def distribution(self, f: np.ndarray, b: int, alpha: tuple = ()) -> tuple[np.ndarray, np.ndarray]:
        """(categories, probabilities) of behaviour ``b`` on entity vector ``f``."""
        alpha = () if alpha is None else alpha
        key = (b, f.tobytes(), alpha)
        if self._owed:
            self._settle(b, key[1])
        if key not in self._cache:
            self.prefetch([f], b, alpha)
        return self._cache[key]

    def _settle(self, b: int, key: bytes) -> None:
        """Make the alpha choices (and their predictions) a prefetch owes for behaviour ``b``
        on the vector of bytes ``key``, if it owes them, exactly as the prefetch would have."""
        v = self._owed.pop((b, key), None)
        if v is not None:
            self._choose_and_predict(v, b)

    @one_blas_thread
    def _choose_and_predict(self, v: np.ndarray, b: int) -> None:
        """Behaviour ``b``'s alpha choices for ``v`` (one batch over the grid), then the chosen
        alphas not predicted yet (grid means need their own predictions; one more batch)."""
        chosen = [a for a in self.alpha_choices(v, b) if (b, v.tobytes(), a) not in self._cache]
        if chosen:
            self._predict_alphas(v, b, chosen)

    def _proba(self, predictor):
        """The predictor's fast probability function where it has one (same numbers)."""
        key = id(predictor)
        if key not in self._fast:
            from afford.learn.predictors import AffordancePredictor, fast_predict_proba

            self._fast[key] = (fast_predict_proba(predictor) if isinstance(predictor, AffordancePredictor)
                               else predictor.predict_proba)
        return self._fast[key]

    def _chosen(self, b: int, key: bytes) -> bool:
        """Are behaviour ``b``'s alpha choices for the vector of bytes ``key``, and their
        predictions, at hand?"""
        chosen = self._choices.get((b, key, self.alpha_rule))
        return chosen is not None and all((b, key, a) in self._cache for a, _ in chosen)

    def cached(self, f: np.ndarray) -> bool:
        """Are every behaviour's predictions for entity vector ``f`` at hand?"""
        key = f.tobytes()
        for b in range(len(self.behaviors)):
            if self._chooses(b):
                if (b, key) in self._owed:
                    continue  # made when first needed, as the prefetch that owes them would have
                chosen = self._choices.get((b, key, self.alpha_rule))
                if chosen is None:
                    return False
                alphas = [a for a, _ in chosen]
            else:
                alphas = self.alphas(b)
            if any((b, key, a) not in self._cache for a in alphas):
                return False
        return True

    def _alpha_columns(self, model: BehaviorModel, alpha: tuple) -> np.ndarray:
        """``alpha`` as the predictor's input columns (an angle as sine and cosine); cached,
        read-only: a search encodes the same few alphas hundreds of thousands of times."""
        key = (id(model), alpha)
        hit = self._columns.get(key)
        if hit is None or hit[0] is not model:
            specs = [{"periodic": bool(model.periodic[j]) if j < len(model.periodic) else False} for j in range(len(alpha))]
            cols = encode_parameters(np.asarray(alpha, dtype=float), specs) if alpha else np.zeros(0)
            cols.setflags(write=False)
            hit = self._columns[key] = (model, cols)
        return hit[1]

    def _alpha_rows(self, model: BehaviorModel, alphas: tuple) -> np.ndarray:
        """:meth:`_alpha_columns` of each of ``alphas``, one row each; cached, read-only."""
        key = (id(model), alphas)
        hit = self._rows.get(key)
        if hit is None or hit[0] is not model:
            rows = np.stack([self._alpha_columns(model, a) for a in alphas])
            rows.setflags(write=False)
            hit = self._rows[key] = (model, rows)
        return hit[1]

    @one_blas_thread
    def prefetch(self, vectors: list[np.ndarray], only: int | None = None, alpha_only: tuple | None = None) -> None:
        """Predict for many entity vectors at once (one call per behaviour and alpha).

        A search needs each new vector's predictions when it expands that state; asking the
        predictors for all of a node's children in one batch costs little more than asking
        for one (scikit-learn's per-call overhead dominates single rows).
        """
        fresh = {v.tobytes(): v for v in vectors}
        for b, model in enumerate(self.behaviors):
            if only is not None and b != only:
                continue
            if self._chooses(b):
                if alpha_only is None:
                    # Each vector's choice of alpha costs a batch over the whole grid (36
                    # rows), and most vectors a search meets are never expanded: the choice
                    # is owed, and made when something first asks about the vector
                    # (:meth:`_settle`), in the same batches as here, so with the same numbers
                    # to the bit (a BLAS product's last bits depend on a row's place in its batch).
                    for key, v in fresh.items():
                        if (b, key) not in self._owed and not self._chosen(b, key):
                            self._owed[(b, key)] = v.copy()  # not a view of a state someone may change
                    continue
                for key in fresh:
                    self._settle(b, key)
            for alpha in self.alphas(b) if alpha_only is None else [alpha_only]:
                todo = [v for key, v in fresh.items() if (b, key, alpha) not in self._cache]
                if not todo:
                    continue
                a = self._alpha_columns(model, alpha)
                X = np.stack([np.concatenate([v[model.selected], a]) for v in todo])
                proba = self._proba(model.predictor)(X)
                if model.known is not None:
                    # the chance that the effect is one of the kinds the categories kept
                    Xk = X if model.known_selected is None else np.stack(
                        [np.concatenate([v[model.known_selected], a]) for v in todo])
                    kept = self._proba(model.known)(Xk)[:, list(model.known.classes_).index(1)]
                    proba = proba * kept[:, None]
                classes = np.asarray(model.predictor.classes_, dtype=int)
                for v, p in zip(todo, proba):
                    self._cache[(b, v.tobytes(), alpha)] = (classes, p)
                self.predictions += len(todo)
                # member effects wait until a vector's effect is asked for (:meth:`effect`):
                # most vectors met are never expanded, and an effect costs about as much
                # alone as in a batch

    def in_hand(self, before: np.ndarray, after: np.ndarray, obj: int) -> bool:
        """Did acting on ``obj`` leave it in the hand? Its height feature rose by more than ``raised``.

        Only a grasp raises an object, and the hand keeps what it raised until its next
        behaviour, which first opens it (sim.behaviors). A robot knows what its own hand
        did; here it reads it off the object's height, perceived or predicted.
        """
        if self.height is None or obj < 0 or not self.visible(after[obj]):
            return False
        return bool(after[obj, self.height] - before[obj, self.height] > self.raised)

    def _members(self, b: int, category: int):
        """Behaviour ``b``'s member effects, where they are used and know ``category``."""
        members = self.behaviors[b].members
        if self.effects == "members" and members is not None and members.has(category):
            return members
        return None

    def _joint_members(self):
        """(behaviours, :class:`JointMembers`) of the behaviours without parameters whose
        member effects are used, where there are two or more; else None."""
        if not hasattr(self, "_joint"):
            from afford.learn.members import JointMembers

            group = [b for b, m in enumerate(self.behaviors)
                     if m.members is not None and m.prototypes is not None and not m.parameters]
            try:
                self._joint = (group, JointMembers([self.behaviors[b].members for b in group])) if len(group) > 1 else None
            except (ValueError, AttributeError):  # effect columns that differ: one behaviour at a time
                self._joint = None
        return self._joint

    def _member_input(self, model: BehaviorModel, f: np.ndarray, alpha: tuple) -> np.ndarray:
        return np.concatenate([f, self._alpha_columns(model, alpha)])

    def effect(self, f: np.ndarray, b: int, category: int, alpha: tuple = ()) -> np.ndarray:
        """The effect category ``category`` of behaviour ``b`` is predicted to have on entity
        ``f``: with member effects, the mean of the effects of the category's members most
        like ``f`` (every category's at once, cached by ``f``'s bytes); else the prototype."""
        model = self.behaviors[b]
        if model.prototypes is None:
            raise DataError(f"behaviour {self.names[b]!r} has no effect prototypes (its labels were given), "
                            "so the next state cannot be predicted")
        if self.effects != "members" or model.members is None:
            return model.prototypes[category]
        key = (b, f.tobytes(), alpha)
        hit = self._effect_cache.get(key)
        if hit is None:
            joint = self._joint_members() if alpha == () else None
            if joint is not None and b in joint[0]:
                # a search asks every behaviour about an object that just changed: answer
                # them all at once (the same numbers as one by one)
                for b2, answer in zip(joint[0], joint[1].means([f] * len(joint[0]))):
                    self._effect_cache[(b2, key[1], ())] = answer
                hit = self._effect_cache[key]
            else:
                hit = self._effect_cache[key] = model.members.means(self._member_input(model, f, alpha))
        means, known = hit
        return means[category] if category < known.size and known[category] else model.prototypes[category]

    def spread(self, f: np.ndarray, b: int, category: int, alpha: tuple = ()) -> np.ndarray:
        """How far the effects :meth:`effect` rests on scatter (standard deviation per feature):
        the nearest members' (members), or every member's of the category (prototype);
        zeros where the model keeps no members."""
        members = self.behaviors[b].members
        if members is None or not members.has(category):
            return np.zeros(len(self.schema))
        if self.effects == "members":
            return members.predict(self._member_input(self.behaviors[b], f, alpha), category)[1]
        return members.category_spread(category)

    def draw_effect(self, f: np.ndarray, b: int, category: int, alpha: tuple, rng: np.random.Generator,
                    whole: bool = False) -> np.ndarray:
        """One effect of category ``category`` on ``f`` as a world might give it.

        By default (``whole=False``): the predicted (mean) effect, with its geometry (where
        the object goes, what goals are mostly about) taken from one of the nearest members'
        own effects (channels whose best count was every member keep the mean: the members
        say nothing of this object there), snapped so that the object lands on a lattice of a
        quarter of each feature's goal tolerance (1.25 cm at the table). Imagined worlds then
        share states, and their replans, where the members' effects lie within that lattice;
        the drawn spread stays.

        ``whole=True``: the whole effect one member had, every channel, geometry snapped the
        same way: one of the members nearest ``f`` (as many as its most local channel
        averages; any member of the category where every channel takes them all). A plan run
        blind (:func:`afford.plan.monitor.blind_probability`) is judged this way, since the
        next step's predictor reads every channel: the mean of several members' shape changes
        can be a shape none of them had (on the crane, the mean of a lying cylinder's
        neighbours' moves shows a flat top that lift calls liftable), and P(next step | mean
        state) is not the mean of P(next step | state).

        Without member effects: the prototype."""
        members = self._members(b, category)
        if members is None:
            return self.effect(f, b, category, alpha)
        x = self._member_input(self.behaviors[b], f, alpha)
        r = int(rng.integers(1 << 30))  # one draw: the same neighbour rank for every channel
        channels = np.asarray(self.schema.channels)
        if whole:  # no mean needed (nor cached: a blind rollout meets a new entity at every draw)
            local = [c for c in dict.fromkeys(channels) if members.k_.get(c, 0) > 0]
            near = min(local, key=lambda c: members.k_[c]) if local else channels[0]
            effects = members.effects(x, category, near)
            return self._snap(f, effects[r % len(effects)].astype(float))
        out = self.effect(f, b, category, alpha).copy()
        cols = self.schema.geometry
        for channel in dict.fromkeys(channels[cols]):
            if members.k_.get(channel, 0) == 0:
                continue  # the prototype predicted this channel best: its members say nothing of this object
            effects = members.effects(x, category, channel)
            mine = cols[channels[cols] == channel]
            out[mine] = effects[r % len(effects)][mine]
        return self._snap(f, out)

    def _snap(self, f: np.ndarray, effect: np.ndarray) -> np.ndarray:
        """``effect`` with its geometry snapped so that ``f`` lands on the lattice of a
        quarter of each feature's goal tolerance (see :meth:`draw_effect`)."""
        out = effect.copy()
        cols = self.schema.geometry
        step = self.schema.tolerances[cols] / 4.0
        out[cols] = np.round((f[cols] + out[cols]) / step) * step - f[cols]
        return out

    def draw_unknown(self, f: np.ndarray, b: int, alpha: tuple, rng: np.random.Generator) -> np.ndarray | None:
        """One effect of a kind the categories discarded, as a world might give it: the whole
        effect one of the discarded members most like ``f`` had (snapped as
        :meth:`draw_effect` snaps). None where there is nothing to draw from: the prototype
        model, or a model without discarded members (an unknown outcome is then taken to
        leave the object as it was)."""
        members = self.behaviors[b].members
        if self.effects != "members" or members is None:
            return None
        pool = members.unknown_effects(self._member_input(self.behaviors[b], f, alpha))
        if pool.shape[0] == 0:
            return None
        return self._snap(f, pool[int(rng.integers(1 << 30)) % pool.shape[0]])

    def _moved(self, before: np.ndarray, b: int, category: int, alpha: tuple = (),
               effect: np.ndarray | None = None) -> np.ndarray:
        """Entity ``before`` after category ``category`` of behaviour ``b`` (vanished: last seen, visibility 0)."""
        f = before + (self.effect(before, b, category, alpha) if effect is None else effect)
        v = self.visibility
        if v is not None and f[v] < 0.5:
            out = before.copy()
            out[v] = 0.0
            return out
        if v is not None:
            f[v] = 1.0
        for h in self.histograms:  # a predicted histogram is still a histogram
            bins = np.maximum(f[h], 0.0)
            total = bins.sum()
            f[h] = bins / total if total > 0 else before[h]
        return f

    def apply(self, state: np.ndarray, obj: int, b: int, category, alpha: tuple = (), effects=None) -> np.ndarray:
        """The state after behaviour ``b`` (parameters ``alpha``) on ``obj`` produced ``category``.

        For a behaviour without a target (``obj`` is :data:`SCENE`), ``category`` holds one
        category per row (None for a row left as it is: an unseen one). ``effects``: the
        effect to add instead of the predicted one (one per row for :data:`SCENE`), as a
        sampled rollout draws it.
        """
        nxt = state.copy()
        if obj == SCENE:
            for i, c in enumerate(category):
                if c is not None:
                    nxt[i] = self._moved(state[i], b, int(c), alpha, None if effects is None else effects[i])
            return nxt
        nxt[obj] = self._moved(state[obj], b, int(category), alpha, effects)
        return nxt

    def outcomes(self, state: np.ndarray, obj: int, b: int, alpha: tuple = (), floor: float | None = None) -> list[Outcome]:
        """Likely outcomes (probability >= ``floor``, by default min_probability), most likely
        first. ``alpha``: the behaviour's parameters; ``()`` or ``None`` for none."""
        floor = self.min_probability if floor is None else floor
        alpha = () if alpha is None else alpha
        if obj == SCENE:
            return self._scene_outcomes(state, b, alpha, floor)
        if not self.visible(state[obj]):
            return []  # the robot cannot act on what it does not see
        classes, proba = self.distribution(state[obj], b, alpha)
        order = np.argsort(-proba, kind="stable")
        return [Outcome(int(classes[i]), float(proba[i]), self.apply(state, obj, b, int(classes[i]), alpha))
                for i in order if proba[i] >= floor]

    def _scene_outcomes(self, state: np.ndarray, b: int, alpha: tuple, floor: float) -> list[Outcome]:
        """Joint outcomes of a behaviour that changes every visible row by its own effect."""
        rows = [i for i in range(state.shape[0]) if self.visible(state[i])]
        choices = []
        for i in rows:
            classes, proba = self.distribution(state[i], b, alpha)
            choices.append([(int(c), float(p)) for c, p in zip(classes, proba) if p >= floor] or [(None, 1.0)])
        out = []
        for combo, p in _joint(choices, floor):
            cats: list = [None] * state.shape[0]
            for i, c in zip(rows, combo):
                cats[i] = c
            out.append(Outcome(tuple(cats), p, self.apply(state, SCENE, b, cats, alpha)))
        out.sort(key=lambda o: -o.probability)
        return out


def _joint(choices: list[list[tuple]], floor: float) -> list[tuple[tuple, float]]:
    """The combinations of ``itertools.product(*choices)`` (each choice a (category,
    probability) pair) whose probability, the product of theirs taken left to right, is at
    least ``floor``: (categories, probability), in ``product``'s order and with its bits.

    A search meets thousands of scenes; with five objects and four likely categories each
    the product has a thousand combinations, nearly all below the floor. A partial product
    that the rest of the row's best choices cannot lift back to the floor ends its branch.
    """
    n = len(choices)
    best = [max(q for _, q in c) for c in choices]
    reach = [1.0] * (n + 1)  # the largest product rows i.. can still give
    for i in range(n - 1, -1, -1):
        reach[i] = reach[i + 1] * best[i]
    out: list[tuple[tuple, float]] = []
    margin = 1.0 - 1e-9  # the bound's own rounding never ends a branch that makes the floor

    def grow(i: int, cats: tuple, p: float) -> None:
        if i == n:
            if p >= floor:
                out.append((cats, p))
            return
        for c, q in choices[i]:
            pq = p * q
            if pq * reach[i + 1] < floor * margin:
                continue
            grow(i + 1, cats + (c,), pq)

    grow(0, (), 1.0)
    return out
