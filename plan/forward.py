"""The forward model: what the robot expects its behaviours to do (thesis 8.6).

For an object f, a behaviour b and its parameters alpha, the predictor gives P(E | f, b,
alpha) over b's effect categories; the next state of that object is f + prototype(E), and
no other object changes (chapter 8). Where the model also learned P(known | f, b, alpha),
the chance that the effect is of a kind its categories kept at all, the category
probabilities are multiplied by it: the rest is an unknown outcome, which no plan counts on. An object that the prototype makes vanish keeps its
last seen position and shape with visibility 0, as perception does.

Predictions depend only on the object's own features, so they are cached by the object's
feature bytes: a search meets the same object vector in many states.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from itertools import product

import numpy as np

__all__ = ["BehaviorModel", "ForwardModel", "Outcome"]


@dataclass
class BehaviorModel:
    """What the planner needs of one learned behaviour."""

    name: str
    predictor: object                  # predict_proba, classes_
    selected: np.ndarray               # object-feature columns the predictor reads
    prototypes: np.ndarray             # (n_categories, d) mean effects
    parameters: list[tuple[float, float]] = field(default_factory=list)  # alpha ranges
    known: object | None = None        # P(the effect is of a kept kind): predict_proba, classes_ [0, 1]
    known_selected: np.ndarray | None = None  # the columns ``known`` reads (None: ``selected``)


@dataclass(frozen=True)
class Outcome:
    category: int
    probability: float
    state: np.ndarray


def _as_slice(index: np.ndarray):
    """``index`` as a slice when it is a run of consecutive integers, else unchanged."""
    if index.ndim == 1 and index.size and index.dtype.kind in "iu" and np.array_equal(index, np.arange(index[0], index[0] + index.size)):
        return slice(int(index[0]), int(index[0]) + index.size)
    return index


class ForwardModel:
    """P(next state | state, behaviour, object, alpha) from learned predictors and prototypes.

    Parameters
    ----------
    behaviors : list of BehaviorModel
    min_probability : float
        Outcomes less likely than this are not expanded by the search.
    param_steps : int
        Grid points per parameter of a parametric behaviour (chapter 9).
    height : int or None
        Index of the object's bottom height (``z_min``): with it the planner knows when a
        step leaves an object in the hand (:meth:`in_hand`).
    raised : float
        Rise (metres) that means an object is held.
    histograms : list of index arrays, optional
        Feature columns that form a normalised histogram (the shape channel's two): after
        adding a prototype they are clipped at 0 and renormalised, so that a predicted
        object stays an object the predictors could have seen.
    """

    def __init__(self, behaviors: list[BehaviorModel], min_probability: float = 0.02, param_steps: int = 5,
                 histograms: list[np.ndarray] | None = None, height: int | None = None, raised: float = 0.05):
        self.behaviors = behaviors
        self.height = height
        self.raised = raised
        # contiguous index runs become slices (much cheaper to index with, per node)
        self.histograms = [_as_slice(np.asarray(h)) for h in (histograms or [])]
        self.names = [b.name for b in behaviors]
        self.min_probability = min_probability
        self.param_steps = param_steps
        self._cache: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}
        self._fast: dict[int, object] = {}
        self.predictions = 0

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise ValueError(f"unknown behaviour {name!r}; the model knows {', '.join(self.names)}") from None

    def alphas(self, b: int) -> list[tuple[float, ...]]:
        """The parameter grid of behaviour ``b`` (one empty tuple for a behaviour without)."""
        ranges = self.behaviors[b].parameters
        if not ranges:
            return [()]
        axes = [np.linspace(lo, hi, self.param_steps) for lo, hi in ranges]
        return [tuple(float(v) for v in p) for p in product(*axes)]

    def distribution(self, f: np.ndarray, b: int, alpha: tuple = ()) -> tuple[np.ndarray, np.ndarray]:
        """(categories, probabilities) of behaviour ``b`` on object vector ``f``."""
        key = (b, f.tobytes(), alpha)
        if key not in self._cache:
            self.prefetch([f], b, alpha)
        return self._cache[key]

    def _proba(self, predictor):
        """The predictor's fast probability function where it has one (same numbers)."""
        key = id(predictor)
        if key not in self._fast:
            from learn.predictors import AffordancePredictor, fast_predict_proba

            self._fast[key] = (fast_predict_proba(predictor) if isinstance(predictor, AffordancePredictor)
                               else predictor.predict_proba)
        return self._fast[key]

    def cached(self, f: np.ndarray) -> bool:
        """Are every behaviour's predictions for object vector ``f`` at hand?"""
        key = f.tobytes()
        return all((b, key, a) in self._cache for b in range(len(self.behaviors)) for a in self.alphas(b))

    def prefetch(self, vectors: list[np.ndarray], only: int | None = None, alpha_only: tuple | None = None) -> None:
        """Predict for many object vectors at once (one call per behaviour and alpha).

        A search needs each new object vector's predictions when it expands that state;
        asking the predictors for all of a node's children in one batch costs little more
        than asking for one (scikit-learn's per-call overhead dominates single rows).
        """
        fresh = {v.tobytes(): v for v in vectors}
        for b, model in enumerate(self.behaviors):
            if only is not None and b != only:
                continue
            for alpha in self.alphas(b) if alpha_only is None else [alpha_only]:
                todo = [v for key, v in fresh.items() if (b, key, alpha) not in self._cache]
                if not todo:
                    continue
                X = np.stack([np.concatenate([v[model.selected], np.asarray(alpha, dtype=float)]) for v in todo])
                proba = self._proba(model.predictor)(X)
                if model.known is not None:
                    # the chance that the effect is one of the kinds the categories kept
                    Xk = X if model.known_selected is None else np.stack(
                        [np.concatenate([v[model.known_selected], np.asarray(alpha, dtype=float)]) for v in todo])
                    kept = self._proba(model.known)(Xk)[:, list(model.known.classes_).index(1)]
                    proba = proba * kept[:, None]
                classes = np.asarray(model.predictor.classes_, dtype=int)
                for v, p in zip(todo, proba):
                    self._cache[(b, v.tobytes(), alpha)] = (classes, p)
                self.predictions += len(todo)

    def in_hand(self, before: np.ndarray, after: np.ndarray, obj: int) -> bool:
        """Did acting on ``obj`` leave it in the hand? It rose by more than ``raised``.

        Only a grasp raises an object, and the hand keeps what it raised until its next
        behaviour, which first opens it (sim.behaviors). A robot knows what its own hand
        did; here it reads it off the object's bottom height, perceived or predicted.
        """
        if self.height is None or after[obj, 0] < 0.5:
            return False
        return bool(after[obj, self.height] - before[obj, self.height] > self.raised)

    def apply(self, state: np.ndarray, obj: int, b: int, category: int) -> np.ndarray:
        """The state after behaviour ``b`` on ``obj`` produced ``category``."""
        nxt = state.copy()
        f = state[obj] + self.behaviors[b].prototypes[category]
        if f[0] < 0.5:  # vanished: the last seen features stay, visibility drops
            nxt[obj, 0] = 0.0
        else:
            f[0] = 1.0
            for h in self.histograms:  # a predicted histogram is still a histogram
                bins = np.maximum(f[h], 0.0)
                total = bins.sum()
                f[h] = bins / total if total > 0 else state[obj, h]
            nxt[obj] = f
        return nxt

    def outcomes(self, state: np.ndarray, obj: int, b: int, alpha: tuple = ()) -> list[Outcome]:
        """Likely outcomes (probability >= min_probability), most likely first."""
        if state[obj, 0] < 0.5:
            return []  # the robot cannot act on what it does not see
        classes, proba = self.distribution(state[obj], b, alpha)
        order = np.argsort(-proba, kind="stable")
        return [Outcome(int(classes[i]), float(proba[i]), self.apply(state, obj, b, int(classes[i])))
                for i in order if proba[i] >= self.min_probability]

    def choose_alpha(self, f: np.ndarray, b: int, rule: str = "probable") -> tuple[tuple, int]:
        """Chapter 9's parameter choice for one behaviour on one object.

        ``"group"``: predict a category for every grid point, take the largest group of
        points predicting the same category, and return the mean of its alphas.
        ``"probable"``: the grid point whose predicted category is most probable.
        """
        grid = self.alphas(b)
        preds = [self.distribution(f, b, a) for a in grid]
        best = [(int(c[np.argmax(p)]), float(p.max())) for c, p in preds]
        if rule == "group":
            cats = [c for c, _ in best]
            top = max(set(cats), key=lambda c: (cats.count(c), -c))
            members = np.array([a for a, c in zip(grid, cats) if c == top])
            return tuple(float(v) for v in members.mean(axis=0)) if members.size else (), top
        i = int(np.argmax([p for _, p in best]))
        return grid[i], best[i][0]
