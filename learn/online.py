"""Curiosity-driven online learning (thesis chapter 6) as stream-based selective sampling.

Candidates arrive one at a time, each with its entity features; acting on one (and so
learning its label) costs an interaction, looking at it costs nothing. Two phases:

- **bootstrap**: the first ``bootstrap`` candidates are all tried; ReliefF on them picks the
  ``n_features`` most relevant features once (the thesis took 250 of 35 100), and a first
  SVM is fitted;
- **curiosity**: each later candidate is tried only if the strategy finds it interesting,
  and the SVM is refitted on everything tried so far (the thesis updated LASVM online;
  refitting a linear SVM on at most a few thousand rows of 250 features costs milliseconds
  here and gives the batch solution exactly).

Strategies (the active-learning field's names):

``random``
    try every candidate (the thesis's baseline: no curiosity);
``margin``
    the thesis's: try when the SVM's output ``|w.x + b|`` is below ``tau`` (0.5 in the
    thesis; its margins lie at 1). With more than two categories, the margin is half the
    gap between the two largest one-vs-rest outputs (the linear SVM's are distances; the
    RBF SVM's are scikit-learn's one-vs-one votes turned into one-vs-rest scores, so
    ``tau`` is on that scale there);
``entropy``
    try when the entropy of calibrated probabilities (Platt's sigmoid, or with more than
    two categories a multinomial logistic regression, fitted out of fold to the SVM's
    outputs), divided by its largest value (log2 of the number of categories: for two
    results, bits), is at least ``threshold`` (0.7: on the planted streams of
    tests/test_online.py, 0.9 stopped trying before the boundary was pinned); with ``budget``, the threshold adapts so
    that about ``budget`` candidates are tried in all (the entropy must reach the quantile
    of those seen that the budget left for the candidates left allows);
``committee``
    try when a committee of ``committee`` SVMs fitted on bootstrap resamples of the tried
    rows does not agree.

:func:`learn_online` takes the labels through ``label(i)``, so a caller can run the
robot's behaviour only for candidates it tries; skipped ones are never labelled.

Labels are given results (chapter 6: the robot's own success reading) or discovered
categories (``categorise``): then ``label(i)`` returns what the robot saw happen (an
effect), the categories are discovered once from the bootstrap's effects (as the
features are chosen once), and every later effect, and the test set's, is named by the
category nearest to it. The learner is a linear SVM (the thesis's) or an RBF one
(``kernel``; chapter 8's predictors are RBF SVMs).
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
    model: object = None              # the last SVM
    encode: Callable | None = None    # with discovered categories: effects -> category ids

    @property
    def n_tried(self) -> int:
        return int(self.tried.sum())


KERNELS = ("linear", "rbf")


def _svm(kernel: str, C: float, seed: int):
    from sklearn.svm import SVC, LinearSVC

    if kernel == "linear":
        # the primal solver: on a few hundred rows of 250 features scaled by the bootstrap's
        # range the dual one took 1500-2600 iterations, 3-6 times as long (the committee's
        # refits dominated figures 6.5-6.6); both solve the same problem, and on figure 6.5's
        # stream their test predictions were identical
        return LinearSVC(C=C, dual=False, max_iter=5000, random_state=seed)
    return SVC(kernel="rbf", C=C, gamma="scale", decision_function_shape="ovr", random_state=seed)


class _Learner:
    """An SVM (linear or RBF) on the chosen features of the rows tried so far, refitted on demand."""

    def __init__(self, columns: np.ndarray, lo: np.ndarray, span: np.ndarray, C: float, seed: int,
                 kernel: str = "linear"):
        self.columns, self.lo, self.span, self.C, self.seed, self.kernel = columns, lo, span, C, seed, kernel
        self.svm = None
        self.constant = None

    def inputs(self, X: np.ndarray) -> np.ndarray:
        return (np.asarray(X)[..., self.columns].astype(float) - self.lo) / self.span  # the chosen columns only

    def fit(self, Z: np.ndarray, y: np.ndarray) -> None:
        if np.unique(y).size < 2:  # one result seen so far: predict it everywhere, certain of nothing
            self.svm, self.constant = None, int(y[0])
            return
        self.svm = _svm(self.kernel, self.C, self.seed).fit(Z, y)
        self.constant = None

    def decision(self, z: np.ndarray) -> np.ndarray:
        """The SVM's outputs: (n,) for two categories, (n, K) one-vs-rest for more."""
        if self.svm is None:
            return np.zeros(len(z))
        return self.svm.decision_function(z)

    def predict(self, Z: np.ndarray) -> np.ndarray:
        if self.svm is None:
            return np.full(len(Z), self.constant)
        return self.svm.predict(Z)


def _margin(d: np.ndarray) -> float:
    """How far one candidate's outputs ``d`` lie from a boundary: ``|d|`` for two
    categories, half the gap between the two largest one-vs-rest outputs for more."""
    d = np.ravel(d)
    if d.size == 1:
        return abs(float(d[0]))
    top = np.sort(d)[-2:]
    return float(top[1] - top[0]) / 2


def _normalised_entropy(p: np.ndarray) -> float:
    """The entropy of the probabilities ``p`` over K categories, in units of log2 K (bits for two)."""
    p = np.ravel(p)
    if p.size == 2:  # bits, with the clip the two-result learner always had (budget ties rest on it)
        q = float(np.clip(p[1], 1e-12, 1 - 1e-12))
        return float(-(q * np.log2(q) + (1 - q) * np.log2(1 - q)))
    p = np.clip(p, 1e-12, 1.0)
    return float(-(p * np.log2(p)).sum() / np.log2(p.size)) if p.size > 1 else 0.0


def _probabilities(calibrator, d: np.ndarray) -> np.ndarray:
    """The calibrated probabilities of one candidate's outputs ``d``; for two categories
    Platt's sigmoid 1 / (1 + exp(a s + b)) written out, as the two-result learner had it."""
    if calibrator.classes_.size == 2:
        s = float(np.ravel(d)[0])
        p = 1.0 / (1.0 + np.exp(-float(calibrator.coef_[0, 0]) * s - float(calibrator.intercept_[0])))
        return np.array([1.0 - p, p])
    return calibrator.predict_proba(_as_columns(d))[0]


def _as_columns(d: np.ndarray) -> np.ndarray:
    return d[:, None] if d.ndim == 1 else d


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
    C: float | None = None,
    kernel: str = "linear",
    categorise: Callable | None = None,
    X_test: np.ndarray | None = None,
    y_test: np.ndarray | None = None,
    every: int = 10,
    seed: int = 0,
) -> OnlineResult:
    """Learn an affordance from a stream of candidates ``X`` (n, d) in arrival order; see
    the module docstring for the phases and strategies.

    ``label(i)`` (or an array, one entry per candidate) gives candidate ``i``'s result once
    it is tried: a given result (an int), or with ``categorise`` what the robot saw happen.
    ``C``: the SVM's; None gives 1 for the linear kernel (the thesis's) and 10 for the RBF
    (on the table's categories, 10 learned faster than 1 and as fast as 100).
    ``categorise(outcomes, rows)`` is called once, on the bootstrap's outcomes and their
    candidate numbers, and returns ``encode(outcomes) -> category ids``, which then names
    every later outcome and the test set's (``y_test`` holds outcomes then). With a test
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
                             committee=committee, n_features=n_features, C=C, kernel=kernel, categorise=categorise,
                             X_test=X_test, y_test=y_test, every=every, seed=seed)


def _learn_online(X, label, strategy, *, bootstrap, tau, threshold, budget, committee, n_features, C, kernel,
                  categorise, X_test, y_test, every, seed) -> OnlineResult:
    from afford.learn.relevance import relieff

    if strategy not in STRATEGIES:
        raise DataError(f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)}")
    if kernel not in KERNELS:
        raise DataError(f"unknown kernel {kernel!r}: choose one of {', '.join(KERNELS)}")
    C = (1.0 if kernel == "linear" else 10.0) if C is None else float(C)
    X = np.asarray(X)  # kept as given (float32 features stay float32: 3000 x 35 100 is 400 MB)
    if X.ndim != 2 or X.dtype.kind not in "iuf":
        raise DataError("the candidates must be a table of numbers, one row per candidate")
    n = X.shape[0]
    if not 2 <= bootstrap <= n:
        raise DataError(f"the bootstrap needs between 2 and {n} candidates (the stream's length), got {bootstrap}")
    raw = (lambda i: label[i]) if isinstance(label, np.ndarray) else label
    rng = np.random.default_rng(seed)
    tried = np.zeros(n, dtype=bool)
    interest = np.full(n, np.nan)
    labels: dict[int, int] = {}
    seen = [raw(i) for i in range(bootstrap)]
    tried[:bootstrap] = True
    if categorise is None:
        encode = None
        get = lambda i: int(raw(i))
        yb = np.array([int(v) for v in seen])
    else:  # the categories, found once from what the bootstrap saw happen
        encode = categorise(seen, list(range(bootstrap)))
        get = lambda i: int(encode([raw(i)])[0])
        yb = np.asarray(encode(seen), dtype=int)
        if y_test is not None:
            y_test = np.asarray(encode(list(y_test)), dtype=int)
    labels.update(zip(range(bootstrap), yb.tolist()))
    # given results may still show the one not seen yet; discovered categories are fixed now
    one_category = encode is not None and np.unique(yb).size < 2
    Xb = X[:bootstrap].astype(float)
    lo = Xb.min(axis=0)
    span = np.where(Xb.max(axis=0) > lo, Xb.max(axis=0) - lo, 1.0)
    if np.unique(yb).size > 1:
        weights = relieff((Xb - lo) / span, yb, random_state=seed)
        columns = np.sort(np.argsort(-weights, kind="stable")[: min(n_features, X.shape[1])])
    else:  # one result in the bootstrap: ReliefF sees no difference; keep the first features
        columns = np.arange(min(n_features, X.shape[1]))
    learner = _Learner(columns, lo[columns], span[columns], C, seed, kernel)
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
    calibrator = None
    members: list = []
    seen_entropy: list[float] = []

    def refit() -> None:
        nonlocal calibrator, members
        y = np.array([labels[i] for i in rows])
        learner.fit(Z[rows], y)
        if strategy == "entropy":
            calibrator = _out_of_fold_calibrator(Z[rows], y, kernel, C, seed)
        elif strategy == "committee":
            members = _committee(Z[rows], y, committee, kernel, C, rng)

    refit()
    for i in range(bootstrap, n):
        z = Z[i:i + 1]
        if strategy == "random":
            go = True
        elif one_category:  # the categories are fixed and there is one: nothing to learn, certain everywhere
            interest[i] = np.inf if strategy == "margin" else 0.0 if strategy == "entropy" else 1.0
            go = False
        elif strategy == "margin":
            interest[i] = _margin(learner.decision(z)[0])
            go = interest[i] < tau
        elif strategy == "entropy":
            # no calibration yet (too few rows, or one result seen): certain of nothing
            interest[i] = 1.0 if calibrator is None else _normalised_entropy(_probabilities(calibrator, learner.decision(z)))
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
    return OnlineResult(tried=tried, selected=columns, curve=curve, interest=interest, model=learner.svm,
                        encode=encode)


def _out_of_fold_calibrator(Z: np.ndarray, y: np.ndarray, kernel: str, C: float, seed: int):
    """Calibration of the SVM's outputs: a logistic regression on the outputs (Platt's
    sigmoid for two categories, multinomial for more) fitted on outputs each row got from
    SVMs that did not see it (3 folds), so the probabilities are not over-confident; None
    (every candidate uncertain) while some category has fewer than 3 rows tried."""
    from sklearn.linear_model import LogisticRegression
    from sklearn.model_selection import StratifiedKFold

    classes, counts = np.unique(y, return_counts=True)
    if classes.size < 2 or counts.min() < 3:
        return None
    scores = np.zeros((len(y), 1 if classes.size == 2 else classes.size))
    for train, test in StratifiedKFold(3, shuffle=True, random_state=seed).split(Z, y):
        svm = _svm(kernel, C, seed).fit(Z[train], y[train])  # every category is in every training split
        scores[test] = _as_columns(svm.decision_function(Z[test]))
    return LogisticRegression(C=1e4).fit(scores, y)


def _committee(Z: np.ndarray, y: np.ndarray, k: int, kernel: str, C: float, rng: np.random.Generator) -> list:
    """``k`` SVMs on bootstrap resamples of the tried rows (a resample with one result is
    that result, a constant vote)."""
    out = []
    for _ in range(k):
        idx = rng.integers(0, len(y), len(y))
        if np.unique(y[idx]).size < 2:
            out.append(int(y[idx[0]]))
            continue
        out.append(_svm(kernel, C, 0).fit(Z[idx], y[idx]))
    return out
