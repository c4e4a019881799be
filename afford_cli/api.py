"""The Python API: what the command line does, callable from a script or a notebook.

Every command runs through these functions, so a script and ``afford ...`` give the same
numbers for the same inputs::

    import afford

    data = afford.explore("table", episodes=20, seed=1)      # Interactions
    afford.save(data, "i.afford", seed=1)
    data = afford.load_interactions("i.afford")
    X, names = data.before_rows(), data.schema.names        # arrays with feature names

    model = afford.load_model("m.afford")                    # after cluster | select-features | train
    classes, p = model.predict_proba("push-forward", X[:5])  # calibrated, rows may sum below 1
    world = afford.world("table", seed=3)                   # a scene to act in
    plan = model.plan(world.perceive(), "0:x>0.15")          # best of three candidate plans
    run = model.execute(world, "0:x>0.15")                    # plan, act, monitor, replan

Errors are :class:`AffordError` (a refused file, an impossible request) or
:class:`afford.features.errors.DataError` (bad values), each one sentence.
"""

from __future__ import annotations

import os
from typing import Callable, Sequence

import numpy as np

from afford.errors import AffordError
from afford.features.errors import DataError
from afford.learning import LoadedModel, read_effects, read_rows
from afford.artifacts import read_artifact

__all__ = [
    "AffordError", "load", "load_interactions", "load_labels", "load_model", "save", "Model",
    "scene_names", "make_scene", "explore", "merge", "navigate", "scene_and_layout", "world", "parse_goal", "to_frame", "cluster", "select_features", "train",
]


def load(path: str):
    """Any artefact: a :class:`Model` for a model file, the :class:`Interactions` of any
    other (interactions, effects, features). ``-`` reads standard input."""
    art = read_artifact(path)
    if art.kind == "model":
        return Model(art)
    from afford.datasets import interactions_from_artifact

    return interactions_from_artifact(art)


def load_interactions(path: str):
    """The interaction rows of an interactions, effects or features artefact."""
    return read_rows(path)[1]


def load_labels(path: str) -> np.ndarray:
    """Each row's label: the effect category ``cluster`` gave it (-1: pruned as rare), or the
    robot's own result where the labels were given (chapters 5-6)."""
    art, data = read_rows(path)
    return read_effects(art, data)[0]


def to_frame(source):
    """A pandas DataFrame of interactions (an artefact's path, or :class:`Interactions`): one
    row per interaction, the features by name (columns in :mod:`afford.export`). Needs the
    ``export`` extra (pandas)."""
    from afford.export import frame_of, to_frame as frame

    return frame(source) if isinstance(source, str) else frame_of(source)


def load_model(path: str) -> "Model":
    """A model artefact with its predictors loaded (only trusted types are ever built)."""
    from afford.learning import load_model as load

    return load(path)


def save(data, path: str, *, seed: int | None = None, episodes: tuple[int, int] | None = None) -> None:
    """Write interactions to an ``interactions`` artefact (atomically; ``-`` is stdout).
    ``episodes`` (start, stop) records that the rows are those episodes whole, as an
    exploration by episodes gives them: what :func:`merge` needs of a shard."""
    from afford.artifacts import artifact_bytes, write_artifact
    from afford.datasets import interactions_members

    if len(data) == 0:
        raise AffordError("there are no interactions to save")
    arrays, meta = interactions_members(data)
    if episodes is not None:
        meta["episodes"] = {"start": int(episodes[0]), "stop": int(episodes[1])}
    write_artifact(path, artifact_bytes("interactions", arrays, meta, seed=seed))


# -- learning: one artefact in, the next out (what cluster | select-features | train do) ------

def cluster(path: str, output: str, *, method: str | None = None, k_max: int | None = None, k: int | dict | None = None,
            prune: str = "frequency", min_fraction: float = 0.03, seed: int = 0, channels: list[str] | None = None,
            progress: Callable[[int, int], None] | None = None) -> dict:
    """Discover effect categories per behaviour (thesis 8.4.1, Algorithm 7): reads an
    ``interactions`` artefact, writes ``effects``; returns the summary ``afford cluster
    --json`` prints. ``progress(done, total)`` is called per behaviour.

    ``method`` None: the scene's own (``clustering`` in its description: chapter 7's
    crane clusters with k-means, lift into 2), else the hierarchical method. ``k``: one
    k for every behaviour or ``{behaviour: k, "*": k}``; given with the scene's method,
    it overrides the scene's k behaviour by behaviour. ``channels``: the effect channels
    categories are formed by (hierarchical); None: the scene's own (chapter 9's grasp:
    visibility, contact point and touch, as tables 9.1-9.2), else every channel. ``k_max``
    None: the scene's own (grasp: 4), else 5.
    The scene's defaults are the thesis's; any option given here overrides them."""
    import time

    from afford.artifacts import artifact_bytes, check_output, write_artifact
    from afford.learn.affordances import discover_effects
    from afford.learning import clustering_settings, effects_members

    check_output(output, [path])
    art, data = read_rows(path)
    if not data.has_after:
        raise AffordError(f"{art.source} records nothing after its behaviours, so it has no effects to cluster; "
                          f"its labels are given ({'/'.join(data.result_names)}): run select-features or train on it directly")
    own = clustering_settings(data.scene, data.schema, art.source, method=method, k=k, channels=channels, k_max=k_max)
    method, k, channels, k_max = own["method"], own["k"], own["channels"], own["k_max"]
    start = time.perf_counter()
    models, labels = discover_effects(data, method=method, k_max=k_max, k=k, prune=prune, min_fraction=min_fraction,
                                      seed=seed, channels=channels, progress=_per_behaviour(progress, data))
    settings = {"method": method, "k_max": k_max, "k": k, "prune": prune, "min_fraction": min_fraction,
                "channels": channels}
    arrays, meta, blobs = effects_members(data, labels, models, settings)
    write_artifact(output, artifact_bytes("effects", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    return {"output": output, "seconds": round(time.perf_counter() - start, 3),
            "channels": [[ch, [data.schema.names[i] for i in idx]] for ch, idx in data.schema.channel_groups()],
            "behaviors": {name: {"n_categories": s["n_categories"], "pruned_rows": s["pruned_rows"],
                                 "categories": s["categories"]} for name, s in meta["effects"].items()}}


def _per_behaviour(progress, data):
    """``progress(done, total)`` as the learners call it, per behaviour finished."""
    return None if progress is None else (lambda done: progress(done, len(data.behaviors)))


def select_features(path: str, output: str, *, method: str = "relieff", top: int | None = None,
                    group_channels: bool = False, kernel: str | None = None, score: str | None = None,
                    seed: int = 0, search_rows: int | None = None, progress: Callable[[int, int], None] | None = None,
                    warn: Callable[[str], None] | None = None) -> dict:
    """Rank the features by relevance to each behaviour's labels (ReliefF, Algorithm 3, or a
    wrapper) and keep the best: reads effects or interactions with given results, writes
    ``features``; returns the summary ``afford select-features --json`` prints. ``score``
    (``"accuracy"`` or ``"log_loss"``: what ReliefF's ranking cut scores) and ``kernel``
    default to the scene's learner, and so does ``search_rows`` (the rows a behaviour the
    ranking's cut cross-validates on, a stratified sample; None: every row). ``warn`` hears,
    before the work starts, when a wrapper faces so many features that it will run for hours."""
    import time

    from afford.artifacts import artifact_bytes, check_output, write_artifact
    from afford.learn.affordances import rank_features
    from afford.learning import features_members, learner_settings, search_rows_setting, selection_score

    # ReliefF's cut is the only step that cross-validates on a sample: with --top, or a
    # wrapper, the rows setting has nothing to act on and is neither used nor recorded.
    cuts = method == "relieff" and top is None
    if search_rows is not None and not cuts:
        raise AffordError(f"--search-rows samples the rows ReliefF's ranking is cut on; "
                          f"{'--top ' + str(top) if top is not None else '--method ' + method} makes no such cut")
    check_output(output, [path])
    art, data = read_rows(path, ("interactions", "effects", "features"))
    labels, _ = read_effects(art, data)
    if top is not None and top > len(data.schema):
        raise AffordError(f"--top {top} is more than the {len(data.schema)} features {art.source} has; "
                          f"give at most {len(data.schema)}")
    kernel_name, _ = learner_settings(art, data, kernel)
    score_name = selection_score(art, data, score)
    if warn is not None:
        cost = wrapper_cost(data.schema, method, group_channels)
        if cost:
            warn(cost)
    start = time.perf_counter()
    rows = search_rows_setting(art, data, search_rows) if cuts else None
    relevance = rank_features(data, labels, method=method, top=top, seed=seed, group_channels=group_channels,
                              kernel=kernel_name, score=score_name, search_rows=rows,
                              progress=_per_behaviour(progress, data))
    settings = {"method": method, "top": top, "group_channels": group_channels, "kernel": kernel_name,
                "score": score_name, **({"search_rows": rows} if rows is not None else {})}
    arrays, meta, blobs = features_members(art, data, relevance, settings)
    write_artifact(output, artifact_bytes("features", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    return {"output": output, "seconds": round(time.perf_counter() - start, 3), "method": method, "score": score_name,
            "behaviors": {n: {"selected": r["selected"], **({"parameters": r["parameters"]} if "parameters" in r else {})}
                          for n, r in meta["relevance"].items()}}


def wrapper_cost(schema, method: str, group_channels: bool = False, folds: int = 5) -> str | None:
    """A sentence on what a wrapper will cost over ``schema``'s features, where it runs for
    hours (None otherwise): backward elimination cross-validates an SVM on every remaining
    unit at every step, some n^2/2 fits; forward selection n per feature it adds."""
    from afford.learn.relevance import feature_groups

    units = int(np.unique(feature_groups(schema)).size) if group_channels else len(schema)
    what = "feature units" if group_channels else "features"
    if method == "backward" and units > 60:
        return (f"backward elimination over {units} {what} fits about {units * (units + 1) // 2 * folds:,} "
                "cross-validated SVMs per behaviour, hours or more here; --method relieff ranks them in seconds")
    if method == "forward" and units > 400:
        return (f"forward selection over {units} {what} fits {units * folds:,} cross-validated SVMs per behaviour "
                "for every feature it adds, hours here; --method relieff ranks them in seconds")
    return None


def train(path: str, output: str, *, kernel: str | None = None, folds: int | None = None, seed: int = 0,
          search_rows: int | None = None, progress: Callable[[int, int], None] | None = None) -> dict:
    """Train each behaviour's calibrated predictor of its labels: reads features, effects or
    interactions with given results, writes ``model``; returns the summary ``afford train
    --json`` prints. ``kernel``, ``folds`` and ``search_rows`` (the rows per behaviour the
    grid search cross-validates on, a stratified sample; None: every row) default to the
    scene's learner."""
    import time

    from afford.artifacts import artifact_bytes, check_output, write_artifact
    from afford.learn.affordances import train_known, train_members, train_predictors
    from afford.learning import learner_settings, model_members, read_selection, search_rows_setting

    check_output(output, [path])
    art, data = read_rows(path, ("interactions", "effects", "features"))
    labels, effects = read_effects(art, data)
    selected = read_selection(art, data)
    kernel_name, n_folds = learner_settings(art, data, kernel, folds)
    rows = search_rows_setting(art, data, search_rows)
    start = time.perf_counter()
    predictors = train_predictors(data, labels, selected, kernel=kernel_name, folds=n_folds, seed=seed,
                                  search_rows=rows, progress=_per_behaviour(progress, data))
    known = train_known(data, labels, seed=seed, search_rows=rows) if effects is not None else None
    members = train_members(data, labels, seed=seed) if effects is not None else None
    settings = {"kernel": kernel_name, "folds": n_folds, "selection": art.kind,
                **({"search_rows": rows} if rows is not None else {})}
    arrays, meta, blobs = model_members(art, data, labels, effects, selected, predictors, settings, known, members)
    write_artifact(output, artifact_bytes("model", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    return {"output": output, "seconds": round(time.perf_counter() - start, 3), "kernel": kernel_name,
            "behaviors": {n: {"cv_accuracy": cv["cv_accuracy"], "best_params": cv["best_params"],
                              "n_categories": len(meta["categories"][n]), "n_features": int(len(selected[n]))}
                          for n, cv in meta["cv"].items()}}


def scene_names() -> list[str]:
    """The registered scenes."""
    from afford.sim.registry import scene_names as names

    return names()


def make_scene(name: str, **options):
    """The scene ``name`` configured with ``options`` (``grid=30``, ``size_max=0.2``, ...)."""
    from afford.sim.registry import make_scene as make

    return make(name, **options)


def explore(scene, *, episodes: int | None = None, interactions: int | None = None, seed: int = 0,
            workers: int = 1, max_steps: int | None = None,
            progress: Callable[[int, int], None] | None = None, episode_start: int = 0,
            backend: str = "loky", scheduler: str | None = None, journal: str | os.PathLike | None = None,
            resume: bool = False, **options):
    """Explore a scene (a name, with its ``options``, or a scene object) with its own loop
    (Algorithm 5 or 1): the :class:`Interactions` recorded.

    Give ``episodes`` (100 when neither is given) or ``interactions``; ``episode_start``
    makes the run one shard of a larger exploration (episodes ``episode_start`` on), to be
    joined with :func:`merge`. The same seed gives the same rows whatever ``workers`` and
    ``backend`` (``"loky"`` on this machine, ``"dask"`` on a LocalCluster of ``workers`` on
    127.0.0.1, or on the running cluster at ``scheduler``). ``journal`` is a folder that
    keeps each finished episode as it arrives: after an interruption (a
    :class:`~afford.errors.Interrupted` names what was kept), ``resume=True`` runs only the
    rest, to the same bytes. Remove the journal once the result is saved.
    ``progress(done, total)`` is called as work finishes.
    """
    from afford.backends import open_pool
    from afford.errors import Interrupted
    from afford.sim.explore import explore as run

    sc = make_scene(scene, **options) if isinstance(scene, str) else scene
    if episodes is None and interactions is None:
        episodes = 100
    book = None
    if journal is not None:
        from pathlib import Path

        from afford.datasets import explored_settings
        from afford.journal import Journal

        identity = {"scene": explored_settings(sc.describe()), "seed": seed, "episodes": episodes, "interactions": interactions,
                    "episode_start": episode_start, "max_steps": max_steps}
        book = Journal.start(Path(journal), identity, resume)
    try:
        with open_pool(backend, workers, scheduler) as pool:
            data = run(sc, episodes=episodes, interactions=interactions, seed=seed, max_steps=max_steps,
                       progress=progress, episode_start=episode_start, pool=pool,
                       done=book.kept if book else None, on_done=book.append if book else None)
    except BaseException as exc:
        if book is None:
            raise
        interrupted = isinstance(exc, KeyboardInterrupt)
        try:
            book.close()
        except OSError:
            # an interruption can land inside a record's write; the reader drops a record cut
            # short, so a failed flush must not turn Ctrl-C into another error
            if not interrupted:
                raise
        if book.created and not book.kept:  # nothing was kept: leave no trace
            book.remove()
            raise
        if interrupted:
            n = book.count()  # what the journal holds whole on disk, which --resume will find
            raise Interrupted(f"interrupted; {n} finished episode{'s are' if n != 1 else ' is'} kept in {book.dir}: "
                              "run the same command with --resume to go on") from None
        raise
    if book is not None:
        book.close()
    if len(data) == 0:
        raise AffordError("exploration recorded no interactions (no object was ever seen)")
    return data


def merge(paths: Sequence[str], output: str) -> dict:
    """Join shards of one exploration (``explore --episode-start/--episode-count``, or
    ``episode_start``) into one ``interactions`` artefact, the same rows a one-shot run gives;
    returns the summary ``afford merge --json`` prints. The shards must share scene, schema
    and seed, and their episodes must neither overlap nor leave a gap."""
    from afford.artifacts import artifact_bytes, check_output, write_artifact
    from afford.datasets import check_shards, interactions_members
    from afford.features import Interactions

    check_output(output, list(paths))
    if len(paths) < 1:
        raise AffordError("give the shards to merge")
    shards = [read_rows(p, ("interactions",)) for p in paths]
    order, (start, stop), seed = check_shards(shards)
    data = Interactions.concatenate([shards[i][1] for i in order])
    arrays, meta = interactions_members(data)
    meta["episodes"] = {"start": start, "stop": stop}
    write_artifact(output, artifact_bytes("interactions", arrays, meta, seed=seed,
                                          parents=[shards[i][0].parent_ref() for i in order]))
    return {"output": output, "shards": len(shards), "interactions": len(data), "episodes": [start, stop],
            "seed": seed}


def scene_and_layout(scene="table", seed: int | None = 0, layout=None, *, allow_empty: bool = False, **drawn):
    """The scene and a layout of it: ``layout`` is a layout file's path or a layout the scene
    parsed; without one it is drawn from ``seed`` (with ``drawn`` options such as
    ``objects=3``), the same one ``afford plan --seed`` draws. An option the scene does not
    take raises :class:`afford.sim.scene.SceneOptionError`; a bad layout, one sentence."""
    from afford.sim.scene import check_options, load_layout_file

    sc = make_scene(scene) if isinstance(scene, str) else scene
    given = {k: v for k, v in drawn.items() if v not in (None, False)}
    check_options(sc, given)
    from_file = isinstance(layout, (str, os.PathLike))
    if layout is None:
        if seed is None:
            raise AffordError("give a layout, or a seed to draw a random one")
        specs = sc.sample(_layout_rng(seed), **given)
    elif from_file:
        specs = load_layout_file(sc, layout)
        if sc.loop == "play" and not specs and not allow_empty:
            raise AffordError(f"{layout} has no [[object]] entries; the robot needs something to act on")
    else:
        specs = layout
    try:
        sc.check_layout(specs)
    except DataError as exc:
        raise DataError(f"{layout if from_file else 'the scene'}: {exc}") from None
    return sc, specs


def world(scene="table", *, seed: int | None = 0, layout=None, **drawn):
    """A simulated world to perceive and act in (``perceive()``, ``act(behaviour, target)``),
    of the scene and layout :func:`scene_and_layout` gives."""
    from afford.sim.session import SimWorld

    sc, specs = scene_and_layout(scene, seed, layout, **drawn)
    return SimWorld(sc, specs, seed or 0)


def _layout_rng(seed: int) -> np.random.Generator:
    """The stream random layouts are drawn from (``--seed`` of plan, emulate and predict)."""
    return np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(7,)))


def parse_goal(goal, schema):
    """A goal from ``"0:x>0.15"``-style expressions (one string, a list, or a Goal)."""
    from afford.plan.goals import Goal, GoalError, parse_goal as parse

    if isinstance(goal, Goal):
        return goal
    try:
        return parse([goal] if isinstance(goal, str) else list(goal), schema)
    except GoalError as exc:
        raise AffordError(str(exc)) from None


class Model(LoadedModel):
    """A learned model: per behaviour the chosen features, a calibrated predictor and, where
    categories were discovered, the effect prototypes the planner chains.

    Attributes: ``names`` (behaviours), ``schema`` (its ``names`` are the feature names),
    ``label_source`` (``discovered`` or ``given``), ``result_names``, ``selected``, and
    ``effect_model``: how :meth:`forward` predicts a category's effect on an entity unless
    told (``members``, or ``prototype`` for the thesis's; set it to compare); ``alpha_rule``:
    how it chooses a behaviour's parameter (``group``, ``probability`` or ``grid``).
    """

    effect_model = "members"
    alpha_rule = "group"

    def forward(self, min_probability: float = 0.02, effects: str | None = None, alpha_rule: str | None = None):
        """The planner's forward model (outcomes below ``min_probability`` are dropped).
        ``effects``: ``members`` (each entity's own effect within its category, the default)
        or ``prototype`` (the thesis's category means); None keeps :attr:`effect_model`.
        ``alpha_rule``: how a one-parameter behaviour's parameter is chosen (``group``,
        thesis 9.5, the default; ``probability``; ``grid``); None keeps :attr:`alpha_rule`."""
        effects = self.effect_model if effects is None else effects
        alpha_rule = self.alpha_rule if alpha_rule is None else alpha_rule
        cache = self.__dict__.setdefault("_forward", {})
        if (min_probability, effects, alpha_rule) not in cache:
            from afford.learning import forward_model

            cache[min_probability, effects, alpha_rule] = forward_model(
                self, min_probability=min_probability, effects=effects, alpha_rule=alpha_rule)
        return cache[min_probability, effects, alpha_rule]

    def _rows(self, X) -> np.ndarray:
        X = np.atleast_2d(np.asarray(X, dtype=float))
        if X.ndim != 2 or X.shape[1] != len(self.schema):
            raise AffordError(f"give feature vectors of {len(self.schema)} features (the model's schema), "
                              f"got an array of shape {np.shape(X)}")
        if not np.all(np.isfinite(X)):
            raise AffordError("feature vectors must be finite numbers")
        return X

    def predict_proba(self, behavior: str, X, alpha: Sequence[float] = ()) -> tuple[np.ndarray, np.ndarray]:
        """(categories, probabilities): for each row of ``X`` (full feature vectors), the
        calibrated probability of each category, times P(known) where the model has one, so
        a row may sum below 1 (the rest is an effect of a kind too rare to keep); the same
        numbers ``afford predict`` and the planner use. ``alpha``: the behaviour's parameters."""
        fm = self.forward(min_probability=0.0)
        b = fm.index(behavior)
        alpha = tuple(float(a) for a in alpha)
        if len(alpha) != len(fm.behaviors[b].parameters):
            raise AffordError(f"{behavior} takes {len(fm.behaviors[b].parameters)} parameters, got {len(alpha)}")
        rows = self._rows(X)
        fm.prefetch(list(rows), only=b, alpha_only=alpha)
        out = [fm.distribution(f, b, alpha) for f in rows]
        classes = out[0][0] if out else np.asarray(self.predictors[behavior].classes_, dtype=int)
        return classes, np.stack([p for _, p in out]) if out else np.zeros((0, classes.size))

    def predict(self, behavior: str, X, alpha: Sequence[float] = ()) -> np.ndarray:
        """The most probable category (or given result's index) for each row of ``X``."""
        classes, p = self.predict_proba(behavior, X, alpha)
        return classes[np.argmax(p, axis=1)] if len(p) else np.zeros(0, dtype=int)

    def predictions(self, state: np.ndarray) -> list[dict]:
        """For each entity of a perceived ``state`` and each behaviour: the probabilities and,
        where effects are predicted, the most probable category's next entity with its
        spread (the standard deviation of the effects it rests on), as the planner assumes
        them (what ``afford predict`` reports)."""
        from afford.plan.forward import SCENE

        fm = self.forward(min_probability=0.0)
        state = np.asarray(state, dtype=float)
        schema = self.schema
        out = []
        for i, f in enumerate(state):
            seen = bool(schema.visible(f))
            entry = {"object": i, "visible": seen, "features": _named(schema, f), "behaviors": {}}
            if seen:
                for b, name in enumerate(self.names):
                    # a behaviour with a parameter: the planner tries the alphas its rule
                    # chose (one per next state); shown is the one whose outcome is surest,
                    # with every choice beside it
                    alphas = fm.alpha_choices(f, b) if fm.behaviors[b].parameters else [()]
                    dists = [fm.distribution(f, b, a) for a in alphas]
                    pick = int(np.argmax([d[1].max() for d in dists]))
                    alpha = alphas[pick]
                    classes, proba = dists[pick]
                    best = int(classes[np.argmax(proba)])
                    p = {"category": best, "probability": round(float(proba.max()), 4),
                         "probabilities": {str(int(c)): round(float(q), 4) for c, q in zip(classes, proba)},
                         # an effect of a kind the model discarded as rare (P(known) < 1), which no plan counts on
                         "unknown": round(max(0.0, 1.0 - float(proba.sum())), 4)}
                    if self.label_source == "given":
                        p["result"] = self.result_names[best]
                    else:
                        obj = SCENE if fm.behaviors[b].target is None else i
                        cats = [best if j == i else None for j in range(state.shape[0])] if obj == SCENE else best
                        nxt = fm.apply(state, obj, b, cats, alpha)[i]
                        # how far the members the prediction rests on scattered (the spread of the effect)
                        spread = fm.spread(f, b, best, alpha)
                        p["next"] = {"visible": bool(schema.visible(nxt)), "features": _named(schema, nxt),
                                     "spread": _named(schema, spread)}
                    if alpha:
                        p["alpha"] = [round(float(a), 3) for a in alpha]
                        p["choices"] = [{"alpha": [round(float(v), 3) for v in a],
                                         "category": int(d[0][np.argmax(d[1])]), "probability": round(float(d[1].max()), 4)}
                                        for a, d in zip(alphas, dists)]
                    entry["behaviors"][name] = p
            out.append(entry)
        return out

    def plans(self, state: np.ndarray, goal, *, alternatives: int = 3, max_replans: int = 3,
              method: str = "best-first", max_depth: int = 5, max_nodes: int = 20000):
        """Candidate plans from a perceived ``state`` to ``goal``, ranked by their probability
        of reaching it with monitoring and up to ``max_replans`` replans, best first."""
        from afford.plan.monitor import rank_plans

        self.check_effects("planning")
        goal = parse_goal(goal, self.schema)
        state = np.asarray(state, dtype=float)
        goal.check_objects(state.shape[0])
        return rank_plans(self.forward(), state, goal, alternatives, max_replans=max_replans, method=method,
                          max_depth=max_depth, max_nodes=max_nodes)

    def plan(self, state: np.ndarray, goal, **limits):
        """The best of :meth:`plans` (``plan.found``, ``plan.steps``, ``plan.success_probability``)."""
        return self.plans(state, goal, **limits)[0]

    def blind_probability(self, state: np.ndarray, goal, plan, *, rollouts: int = 200, seed: int = 0) -> float:
        """P(``goal`` holds after some step of ``plan`` run blind from ``state``, with no
        monitoring), by imagined worlds that draw each step's whole effect from one of the
        nearest members (:func:`afford.plan.monitor.blind_probability`)."""
        from afford.plan.monitor import blind_probability

        goal = parse_goal(goal, self.schema)
        state = np.asarray(state, dtype=float)
        goal.check_objects(state.shape[0])
        return blind_probability(self.forward(), state, goal, plan, rollouts=rollouts, seed=seed)

    def execute(self, world, goal, *, first=None, alternatives: int = 3, max_replans: int = 3,
                method: str = "best-first", max_depth: int = 5, max_nodes: int = 20000, say=None):
        """Plan in ``world`` (see :func:`world`; ``first``: a plan already made there), act,
        compare each step with its prediction, and replan on a surprise (each replan chosen
        among ``alternatives`` the same way): the :class:`afford.plan.monitor.Execution`.
        ``say(line)`` hears each step, its outcome and each replan as they happen."""
        from afford.plan.monitor import execute as run
        from afford.plan.monitor import ranked_planner

        self.check_schema(world.scene.schema, "this scene's perception")
        limits = {"max_depth": max_depth, "max_nodes": max_nodes}
        if first is None:
            first = self.plan(world.perceive(), goal, alternatives=alternatives, max_replans=max_replans,
                              method=method, **limits)
        goal = parse_goal(goal, self.schema)
        planner = ranked_planner(self.forward(), goal, alternatives, max_replans=max_replans, method=method, **limits)
        return run(world, self.forward(), goal, method=method, max_replans=max_replans, first=first,
                   planner=planner, say=say, **limits)

    def inverse(self, state: np.ndarray, want) -> list[dict]:
        """Inverse query: (object, behaviour, alpha) ranked by the probability that one step
        makes ``want`` hold."""
        from afford.plan.search import inverse_query

        self.check_effects("an inverse query")
        goal = parse_goal(want, self.schema)
        state = np.asarray(state, dtype=float)
        goal.check_objects(state.shape[0])
        return inverse_query(self.forward(min_probability=0.0), state, goal)


#: Geometry features named per entity, at most: a grasp's 24 measurements are all given; a
#: range image's grid of 300 cells, none (its entity is the whole scene, not an object).
_SHOWN = 64


def navigate(model, *, scene: str = "room", controller: str = "aggressive", seed: int = 0, room: int | None = None,
             steps: int = 100, threshold: float = 0.5) -> dict:
    """Drive the mobile robot through a room with a traverse model (a path or a loaded model),
    as ``afford navigate`` does (thesis 5.6.5): the report, with ``distance_m``, ``moves``,
    ``failed_moves``, ``stuck`` and the true ``path`` in the room's frame. ``seed`` picks the
    room (unless ``room``) and where the robot starts."""
    from afford.navigation import navigate as run

    loaded = load_model(model) if isinstance(model, (str, os.PathLike)) else model
    sc = make_scene(scene)
    if "room" in sc.options:
        sc = make_scene(scene, room=seed if room is None else room)
    return run(loaded, sc, controller, seed=seed, steps=steps, threshold=threshold)


def _named(schema, f: np.ndarray) -> dict:
    cols = schema.geometry
    if cols.size > _SHOWN:
        return {}
    return {schema.names[i]: round(float(f[i]), 4) for i in cols}
