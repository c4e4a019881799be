"""Curiosity-driven online learning (thesis chapter 6) as stream-based selective sampling.

Candidates arrive one at a time, each with its entity features; acting on one (and so
learning its label) costs an interaction, looking at it costs nothing. Two phases:

- **bootstrap**: the first ``bootstrap`` candidates are all tried; ReliefF on them picks the
  ``n_features`` most relevant features once (the thesis took 250 of 35 100), and a first
  linear SVM is fitted;
- **curiosity**: each later candidate is tried only if the strategy finds it interesting,
  and the SVM is refitted on everything tried so far (the thesis updated LASVM online;
  refitting a linear SVM on at most a few thousand rows of 250 features costs milliseconds
  here and gives the batch solution exactly).

Strategies (the active-learning field's names):

``random``
    try every candidate (the thesis's baseline: no curiosity);
``margin``
    the thesis's: try when the SVM's output ``|w.x + b|`` is below ``tau`` (0.5 in the
    thesis; its margins lie at 1);
``entropy``
    try when the entropy of calibrated probabilities (a sigmoid fitted out of fold to the
    SVM's outputs) is at least ``threshold`` bits (0.7: on the planted streams of
    tests/test_online.py, 0.9 stopped trying before the boundary was pinned); with ``budget``, the threshold adapts so
    that about ``budget`` candidates are tried in all (the entropy must reach the quantile
    of those seen that the budget left for the candidates left allows);
``committee``
    try when a committee of ``committee`` SVMs fitted on bootstrap resamples of the tried
    rows does not agree.

:func:`learn_online` takes the labels through ``label(i)``, so a caller can run the
robot's behaviour only for candidates it tries; skipped ones are never labelled.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from afford.features.errors import DataError

__all__ = ["STRATEGIES", "OnlineResult", "learn_online"]

STRATEGIES = ("random", "margin", "entropy", "committee")


@dataclass
class OnlineResult:
    """What a stream of candidates taught, and at what cost."""

    tried: np.ndarray                 # (n,) bool: the candidates acted on (their labels learned)
    selected: np.ndarray              # feature columns chosen from the bootstrap
    curve: list[dict] = field(default_factory=list)  # {"interactions", "accuracy"} on the test set
    interest: np.ndarray | None = None  # (n,) the score the strategy looked at (nan in the bootstrap)
    model: object = None              # the last linear SVM

    @property
    def n_tried(self) -> int:
        return int(self.tried.sum())


class _Learner:
    """A linear SVM on the chosen features of the rows tried so far, refitted on demand."""

    def __init__(self, columns: np.ndarray, lo: np.ndarray, span: np.ndarray, C: float, seed: int):
        self.columns, self.lo, self.span, self.C, self.seed = columns, lo, span, C, seed
        self.svm = None
        self.constant = None

    def inputs(self, X: np.ndarray) -> np.ndarray:
        return (np.asarray(X)[..., self.columns].astype(float) - self.lo) / self.span  # the chosen columns only

    def fit(self, Z: np.ndarray, y: np.ndarray) -> None:
        from sklearn.svm import LinearSVC

        if np.unique(y).size < 2:  # one result seen so far: predict it everywhere, certain of nothing
            self.svm, self.constant = None, int(y[0])
            return
        self.svm = LinearSVC(C=self.C, dual="auto", max_iter=5000, random_state=self.seed).fit(Z, y)
        self.constant = None

    def decision(self, z: np.ndarray) -> np.ndarray:
        if self.svm is None:
            return np.zeros(len(z))
        return self.svm.decision_function(z)

    def predict(self, Z: np.ndarray) -> np.ndarray:
        if self.svm is None:
            return np.full(len(Z), self.constant)
        return self.svm.predict(Z)


def _entropy(p: np.ndarray) -> np.ndarray:
    p = np.clip(p, 1e-12, 1 - 1e-12)
    return -(p * np.log2(p) + (1 - p) * np.log2(1 - p))


def _sigmoid_fit(scores: np.ndarray, y: np.ndarray) -> tuple[float, float]:
    """Platt's sigmoid P(y=1 | s) = 1 / (1 + exp(a s + b)), fitted by logistic regression."""
    from sklearn.linear_model import LogisticRegression

    if np.unique(y).size < 2:
        return 0.0, 0.0
    lr = LogisticRegression(C=1e4).fit(scores[:, None], y)
    return -float(lr.coef_[0, 0]), -float(lr.intercept_[0])


def learn_online(
    X: np.ndarray,
    label: Callable[[int], int] | np.ndarray,
    strategy: str = "margin",
    *,
    bootstrap: int = 25,
    tau: float = 0.5,
    threshold: float = 0.7,
    budget: int | None = None,
    committee: int = 5,
    n_features: int = 250,
    C: float = 1.0,
    X_test: np.ndarray | None = None,
    y_test: np.ndarray | None = None,
    every: int = 10,
    seed: int = 0,
) -> OnlineResult:
    """Learn a binary affordance (0/1 results) from a stream of candidates ``X`` (n, d) in
    arrival order; see the module docstring for the phases and strategies.

    ``label(i)`` (or an array) gives candidate ``i``'s result once it is tried. With a test
    set, ``curve`` holds the test accuracy after the bootstrap and after every ``every``
    tried candidates, and after the last.
    """
    import warnings

    from sklearn.exceptions import ConvergenceWarning

    with warnings.catch_warnings():
        # liblinear stops at its iteration cap on some early fits (a handful of rows in many
        # dimensions); the SVM it returns is still the one a capped online learner has
        warnings.simplefilter("ignore", ConvergenceWarning)
        return _learn_online(X, label, strategy, bootstrap=bootstrap, tau=tau, threshold=threshold, budget=budget,
                             committee=committee, n_features=n_features, C=C, X_test=X_test, y_test=y_test,
                             every=every, seed=seed)


def _learn_online(X, label, strategy, *, bootstrap, tau, threshold, budget, committee, n_features, C, X_test, y_test,
                  every, seed) -> OnlineResult:
    from afford.learn.relevance import relieff

    if strategy not in STRATEGIES:
        raise DataError(f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)}")
    X = np.asarray(X)  # kept as given (float32 features stay float32: 3000 x 35 100 is 400 MB)
    if X.ndim != 2 or X.dtype.kind not in "iuf":
        raise DataError("the candidates must be a table of numbers, one row per candidate")
    n = X.shape[0]
    if not 2 <= bootstrap <= n:
        raise DataError(f"the bootstrap needs between 2 and {n} candidates (the stream's length), got {bootstrap}")
    get = (lambda i: int(label[i])) if isinstance(label, np.ndarray) else (lambda i: int(label(i)))
    rng = np.random.default_rng(seed)
    tried = np.zeros(n, dtype=bool)
    interest = np.full(n, np.nan)
    labels: dict[int, int] = {}
    for i in range(bootstrap):
        labels[i] = get(i)
        tried[i] = True
    Xb = X[:bootstrap].astype(float)
    yb = np.array([labels[i] for i in range(bootstrap)])
    lo = Xb.min(axis=0)
    span = np.where(Xb.max(axis=0) > lo, Xb.max(axis=0) - lo, 1.0)
    if np.unique(yb).size > 1:
        weights = relieff((Xb - lo) / span, yb, random_state=seed)
        columns = np.sort(np.argsort(-weights, kind="stable")[: min(n_features, X.shape[1])])
    else:  # one result in the bootstrap: ReliefF sees no difference; keep the first features
        columns = np.arange(min(n_features, X.shape[1]))
    learner = _Learner(columns, lo[columns], span[columns], C, seed)
    Z = learner.inputs(X)
    rows = list(range(bootstrap))
    learner.fit(Z[rows], yb)
    Zt = None if X_test is None else learner.inputs(X_test)
    curve: list[dict] = []

    def score() -> None:
        if Zt is not None and y_test is not None:
            acc = float(np.mean(learner.predict(Zt) == np.asarray(y_test)))
            curve.append({"interactions": len(rows), "accuracy": round(acc, 4)})

    score()
    sigmoid = (0.0, 0.0)
    members: list = []
    seen_entropy: list[float] = []

    def refit() -> None:
        nonlocal sigmoid, members
        y = np.array([labels[i] for i in rows])
        learner.fit(Z[rows], y)
        if strategy == "entropy":
            sigmoid = _out_of_fold_sigmoid(Z[rows], y, C, seed)
        elif strategy == "committee":
            members = _committee(Z[rows], y, committee, C, rng)

    refit()
    for i in range(bootstrap, n):
        z = Z[i:i + 1]
        if strategy == "random":
            go = True
        elif strategy == "margin":
            interest[i] = abs(float(learner.decision(z)[0]))
            go = interest[i] < tau
        elif strategy == "entropy":
            a, b = sigmoid
            p = 1.0 / (1.0 + np.exp(a * learner.decision(z) + b))
            interest[i] = float(_entropy(p)[0])
            seen_entropy.append(interest[i])
            if budget is None:
                go = interest[i] >= threshold
            else:
                left = budget - len(rows)
                share = left / max(n - i, 1)
                go = left > 0 and interest[i] >= np.quantile(seen_entropy, max(0.0, 1.0 - share))
        else:
            votes = [m.predict(z)[0] if hasattr(m, "predict") else m for m in members]
            interest[i] = float(np.mean(np.asarray(votes) == votes[0]))
            go = interest[i] < 1.0
        if not go:
            continue
        labels[i] = get(i)
        tried[i] = True
        rows.append(i)
        due = (len(rows) - bootstrap) % every == 0
        if strategy != "random" or due:  # random never asks the model: fit it only to score it
            refit()
        if due:
            score()
    if not curve or curve[-1]["interactions"] != len(rows):
        if strategy == "random":
            refit()
        score()
    return OnlineResult(tried=tried, selected=columns, curve=curve, interest=interest, model=learner.svm)


def _out_of_fold_sigmoid(Z: np.ndarray, y: np.ndarray, C: float, seed: int) -> tuple[float, float]:
    """Platt scaling of the SVM's outputs, fitted on outputs each row got from SVMs that did
    not see it (3 folds), so the probabilities are not over-confident."""
    from sklearn.model_selection import StratifiedKFold
    from sklearn.svm import LinearSVC

    counts = np.bincount(y, minlength=2)
    if counts.min() < 3:
        return 0.0, 0.0  # too few of one result to fold: every candidate is uncertain
    scores = np.zeros(len(y))
    for train, test in StratifiedKFold(3, shuffle=True, random_state=seed).split(Z, y):
        if np.unique(y[train]).size < 2:
            return 0.0, 0.0
        svm = LinearSVC(C=C, dual="auto", max_iter=5000, random_state=seed).fit(Z[train], y[train])
        scores[test] = svm.decision_function(Z[test])
    return _sigmoid_fit(scores, y)


def _committee(Z: np.ndarray, y: np.ndarray, k: int, C: float, rng: np.random.Generator) -> list:
    """``k`` linear SVMs on bootstrap resamples of the tried rows (a resample with one result
    is that result, a constant vote)."""
    from sklearn.svm import LinearSVC

    out = []
    for _ in range(k):
        idx = rng.integers(0, len(y), len(y))
        if np.unique(y[idx]).size < 2:
            out.append(int(y[idx[0]]))
            continue
        out.append(LinearSVC(C=C, dual="auto", max_iter=5000, random_state=0).fit(Z[idx], y[idx]))
    return out
