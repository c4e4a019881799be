"""Relevant features: which object features tell a behaviour's effect categories apart.

Three methods from the thesis:

ReliefF (chapter 5, Algorithm 3)
    A filter: ``m`` random interactions; for each, its ``k`` nearest hits (same category)
    and, per other category, ``k`` nearest misses; a feature gains weight when it differs
    on misses and loses it when it differs on hits. Features are min-max normalised and
    distances are Manhattan (sum of normalised differences), as in Kononenko's ReliefF;
    misses of each class are weighted by that class's prior, ``P(C) / (1 - P(class))``.
Forward selection (the thesis's ``sequentialfs``, chapter 5.7)
    A wrapper: start from no feature and add the one whose addition gives the best
    cross-validated accuracy, while the accuracy rises by more than ``tol``.
Backward elimination (the "Schemata search" of chapter 8.5.3)
    A wrapper: start from all features and remove the one (or the group: the thesis
    treated each normal-angle histogram as one unit) whose removal hurts cross-validated
    accuracy least, while the accuracy stays within ``tol`` of the best seen.

The wrappers use one set of stratified folds for every candidate, so candidates are
compared on the same data. Their default classifier is a 10-nearest-neighbour vote on
standardised features: it is nonlinear (reachability and graspability are thresholds and
bands), needs no tuning, and costs milliseconds per fold, where the thesis's SVMs would make
the hundreds of candidate fits of a wrapper take minutes. Pass ``estimator=`` to change it.
"""

from __future__ import annotations

import numbers
import warnings

import numpy as np
from joblib import Parallel, delayed
from scipy.spatial.distance import cdist
from sklearn.base import BaseEstimator, clone
from sklearn.model_selection import StratifiedKFold
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_array, check_is_fitted, validate_data

from afford.features.errors import DataError
from afford.features.schema import FeatureSchema
from afford.learn.validation import check_finite, stratified_sample

__all__ = ["FeatureRelevance", "backward_elimination", "feature_groups", "forward_selection", "ranking_prefix", "relieff"]

# Rows of sampled instances whose distances to all rows are computed at once (memory bound).
_CHUNK = 256


def _check_Xy(X, y, min_rows: int = 2):
    X = check_array(X, dtype=np.float64, ensure_all_finite=False)
    check_finite(X)
    y = np.asarray(y)
    if y.ndim != 1 or y.shape[0] != X.shape[0]:
        raise DataError(f"y must be one label per row of X: X has {X.shape[0]} rows, y has shape {y.shape}.")
    check_classification_targets(y)
    classes, y_idx = np.unique(y, return_inverse=True)
    if classes.size < 2:
        raise DataError(f"feature relevance needs at least two effect categories, but y holds only one class ({classes[0]!r}).")
    if X.shape[0] < min_rows:
        raise DataError(f"X has {X.shape[0]} rows, too few to estimate feature relevance (need at least {min_rows}).")
    return X, y, classes, y_idx


def feature_groups(schema) -> np.ndarray:
    """Group label per feature, as the schema declares: each histogram is one group.

    This makes each 18-bin normal-angle histogram one unit for the wrappers, as in the
    thesis's Schemata search; every other feature is a group of its own.

    Parameters
    ----------
    schema : FeatureSchema or sequence of str
        A schema, or feature names (each then its own group).

    Returns
    -------
    groups : ndarray of shape (n_features,)
        Integer group labels, numbered in order of first appearance.
    """
    if isinstance(schema, FeatureSchema):
        return schema.groups()
    return np.arange(len(tuple(schema)), dtype=int)


def relieff(X, y, n_samples=1000, n_neighbors=10, random_state=None) -> np.ndarray:
    """ReliefF feature weights (Algorithm 3), vectorised.

    Parameters
    ----------
    X : array-like of shape (n_rows, n_features)
    y : array-like of shape (n_rows,)
        Effect category of each row.
    n_samples : int, default=1000
        ``m``, the number of sampled rows (1000 in the thesis); all rows when there are
        fewer. Neighbours are searched among all rows.
    n_neighbors : int, default=10
        ``k`` hits and ``k`` misses per other class (10 in the thesis); fewer when a class
        has fewer members.
    random_state : int, RandomState instance or None, default=None

    Returns
    -------
    weights : ndarray of shape (n_features,)
        Higher is more relevant; about 0 for noise, at most 1. Constant features get 0.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> X = rng.random((300, 4))
    >>> y = (X[:, 2] > 0.5).astype(int)
    >>> int(np.argmax(relieff(X, y, random_state=0)))
    2
    """
    X, y, classes, y_idx = _check_Xy(X, y)
    if n_samples < 1 or n_neighbors < 1:
        raise DataError("n_samples and n_neighbors must be at least 1.")
    rng = check_random_state(random_state)
    n, d = X.shape
    span = X.max(axis=0) - X.min(axis=0)
    Xn = (X - X.min(axis=0)) / np.where(span > 0, span, 1.0)
    prior = np.bincount(y_idx) / n
    members = [np.flatnonzero(y_idx == c) for c in range(classes.size)]
    m = min(n_samples, n)
    sample = np.sort(rng.choice(n, m, replace=False))
    k = n_neighbors
    weights = np.zeros(d)
    for start in range(0, m, _CHUNK):
        rows = sample[start : start + _CHUNK]
        R = Xn[rows]
        D = cdist(R, Xn, metric="cityblock")
        D[np.arange(rows.size), rows] = np.inf  # a row is not its own neighbour
        own = y_idx[rows]
        for c, idx in enumerate(members):
            Dc = D[:, idx]
            kc = min(k, idx.size)
            nn = np.argpartition(Dc, kc - 1, axis=1)[:, :kc] if kc < idx.size else np.tile(np.arange(idx.size), (rows.size, 1))
            valid = np.isfinite(np.take_along_axis(Dc, nn, axis=1))  # drops the row itself
            diff = np.abs(Xn[idx[nn]] - R[:, None, :])  # (rows, kc, d)
            count = valid.sum(axis=1)
            mean_diff = (diff * valid[:, :, None]).sum(axis=1) / np.maximum(count, 1)[:, None]
            hit = own == c
            coef = np.where(hit, -1.0, prior[c] / (1.0 - prior[own]))
            coef[count == 0] = 0.0
            weights += (coef[:, None] * mean_diff).sum(axis=0)
    return weights / m


def _units(groups, d: int) -> list[np.ndarray]:
    if groups is None:
        return [np.array([j]) for j in range(d)]
    groups = np.asarray(groups)
    if groups.shape != (d,):
        raise DataError(f"feature groups must give one group per feature: X has {d} features, groups has shape {groups.shape}.")
    return [np.flatnonzero(groups == g) for g in dict.fromkeys(groups.tolist())]


class _NearestNeighbourCV:
    """Cross-validated accuracy of a k-NN vote on standardised features, for many subsets.

    The wrappers' default classifier, written for their access pattern: squared
    Euclidean distances are sums over features, so the distances of a subset with one unit
    more (forward) or less (backward) are the current distances plus or minus that unit's
    share, and every candidate costs one neighbour search instead of a model fit. Same
    result as ``make_pipeline(StandardScaler(), KNeighborsClassifier(k))`` up to ties.
    """

    def __init__(self, X, y, folds, k=10):
        self.y = y
        self.n_classes = int(y.max()) + 1
        self.parts = []
        for train, test in folds:
            mu = X[train].mean(axis=0)
            sd = X[train].std(axis=0)
            sd = np.where(sd > 0, sd, 1.0)
            self.parts.append(((X[train] - mu) / sd, (X[test] - mu) / sd, y[train], y[test]))
        self.k = k
        self.base = None

    @staticmethod
    def _sq(a, b):
        return cdist(a, b, metric="sqeuclidean") if a.shape[1] else np.zeros((a.shape[0], b.shape[0]))

    def set_base(self, cols):
        """Distances on the current subset, per fold."""
        self.base = [self._sq(te[:, cols], tr[:, cols]) for tr, te, _, _ in self.parts]

    def _vote_accuracy(self, D, ytr, yte):
        k = min(self.k, D.shape[1])
        nn = np.argpartition(D, k - 1, axis=1)[:, :k] if k < D.shape[1] else np.argsort(D, axis=1)
        votes = np.zeros((D.shape[0], self.n_classes))
        np.add.at(votes, (np.arange(D.shape[0])[:, None], ytr[nn]), 1.0)
        return float(np.mean(votes.argmax(axis=1) == yte))

    def accuracy(self, cols):
        if cols.size == 0:
            return _majority_accuracy(self.parts)
        accs = []
        for tr, te, ytr, yte in self.parts:
            accs.append(self._vote_accuracy(self._sq(te[:, cols], tr[:, cols]), ytr, yte))
        return float(np.mean(accs))

    def accuracy_changed(self, unit, sign):
        """Accuracy of the base subset with ``unit`` added (sign=+1) or removed (-1)."""
        accs = []
        for D, (tr, te, ytr, yte) in zip(self.base, self.parts):
            accs.append(self._vote_accuracy(D + sign * self._sq(te[:, unit], tr[:, unit]), ytr, yte))
        return float(np.mean(accs))


def _majority_accuracy(parts):
    """Accuracy of predicting each training fold's most frequent category (no feature)."""
    accs = []
    for _, _, ytr, yte in parts:
        values, counts = np.unique(ytr, return_counts=True)
        accs.append(np.mean(yte == values[np.argmax(counts)]))
    return float(np.mean(accs))


class _EstimatorCV:
    """Cross-validated accuracy of any classifier on feature subsets (refits every time)."""

    def __init__(self, estimator, X, y, folds, n_jobs=None):
        self.estimator, self.X, self.y, self.folds, self.n_jobs = estimator, X, y, folds, n_jobs
        self.parts = [(None, None, y[tr], y[te]) for tr, te in folds]
        self.base = None

    def accuracy(self, cols):
        if cols.size == 0:
            return _majority_accuracy(self.parts)
        Xc = self.X[:, cols]
        accs = []
        for train, test in self.folds:
            model = clone(self.estimator).fit(Xc[train], self.y[train])
            accs.append(np.mean(model.predict(Xc[test]) == self.y[test]))
        return float(np.mean(accs))

    def set_base(self, cols):
        self.base = cols

    def accuracy_changed(self, unit, sign):
        cols = np.concatenate([self.base, unit]) if sign > 0 else np.setdiff1d(self.base, unit)
        return self.accuracy(cols)


def _evaluator(estimator, X, y, cv, random_state, n_jobs):
    folds = _folds(y, cv, check_random_state(random_state).randint(np.iinfo(np.int32).max))
    if estimator is None:
        return _NearestNeighbourCV(X, y, folds)
    return _EstimatorCV(estimator, X, y, folds, n_jobs)


def _folds(y, cv, seed):
    n = y.shape[0]
    if n < 2 * cv:
        raise DataError(f"X has {n} rows, too few to cross-validate with cv={cv} (need at least {2 * cv}).")
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message="The least populated class")
        return list(StratifiedKFold(cv, shuffle=True, random_state=seed).split(np.zeros(n), y))


def _score_changes(evaluator, units, sign, n_jobs):
    """Accuracy of the evaluator's base subset with each unit added or removed."""
    if n_jobs in (None, 1):
        return [evaluator.accuracy_changed(u, sign) for u in units]
    return Parallel(n_jobs=n_jobs, prefer="threads")(delayed(evaluator.accuracy_changed)(u, sign) for u in units)


def _prefix_sizes(d: int) -> list[int]:
    """Candidate prefix lengths: every size up to 4, then about a third more each time."""
    sizes, k = [], 1
    while k < d:
        sizes.append(k)
        k = k + 1 if k < 4 else int(round(k * 4 / 3))
    return sizes + [d]


def _temperature_log_loss(D, y, fit_rows, eval_rows):
    """Mean log loss on ``eval_rows`` of ``softmax(D / T)``, with the one temperature ``T``
    fitted (by log loss) on ``fit_rows``: the calibration ``train`` applies, fitted out of
    sample."""
    from scipy.optimize import minimize_scalar
    from scipy.special import log_softmax

    def nll(log_t, rows):
        return float(-np.mean(log_softmax(D[rows] / np.exp(log_t), axis=1)[np.arange(rows.size), y[rows]]))

    log_t = minimize_scalar(nll, bounds=(-6.0, 6.0), args=(fit_rows,), method="bounded").x
    return nll(log_t, eval_rows)


def _margins(model, X, n_classes):
    """Per-category decision values of a fitted classifier, one column per category of all
    ``n_classes`` (a category its training fold lacked gets a margin far below the rest).
    A classifier without margins (a forest) gives its log-probabilities."""
    if hasattr(model, "decision_function"):
        D = np.asarray(model.decision_function(X), dtype=float)
    else:
        D = np.log(np.asarray(model.predict_proba(X), dtype=float) + 1e-6)
    if D.ndim == 1:  # binary: one margin, for the second class
        D = np.column_stack([-D / 2, D / 2])
    out = np.full((D.shape[0], n_classes), -1e3 + D.min() if D.size else -1e3)
    out[:, np.asarray(model.classes_, dtype=int)] = D
    return out


def ranking_prefix(X, y, ranking, estimator=None, cv=3, random_state=None, n_jobs=None, scoring="accuracy"):
    """How many of the best-ranked features to keep, by cross-validation.

    A filter ranks but does not say where to stop. Prefixes of ``ranking`` of growing
    length (1, 2, 3, 4, then about a third longer each time, and all) are scored by
    stratified cross-validation (the same folds for each), and the shortest prefix whose
    score is within one standard error of the best one is kept: noisy features dilute
    an RBF kernel's distances, so a short prefix often predicts better than all of them.

    Accuracy only counts the most probable category, so a feature that makes a rare
    category likelier without ever making it the likeliest (where a grasp lifts: 4-6 % of
    grasps) gains nothing by it. ``scoring="log_loss"`` scores the probabilities instead:
    each fold's per-category margins are turned into probabilities by one softmax
    temperature, as ``train`` calibrates, fitted on one half of the held-out rows and
    scored on the other (and the other way round).

    Parameters
    ----------
    X : array-like of shape (n_rows, n_features)
    y : array-like of shape (n_rows,)
    ranking : array-like of int
        Feature indices, most relevant first.
    estimator : classifier or None, default=None
        None: an RBF SVM (C=100, ``gamma="scale"``) on standardised features, the
        predictor ``afford train`` fits, without its grid search; for ``"log_loss"`` one
        such machine per category against the rest, as ``train``'s. Given, it must have a
        ``decision_function`` for ``"log_loss"``.
    cv : int, default=3
    random_state : int, RandomState instance or None, default=None
        Seeds the folds.
    n_jobs : int or None, default=None
    scoring : {"accuracy", "log_loss"}, default="accuracy"

    Returns
    -------
    k : int
        Number of features to keep.
    path : list of dict
        ``{"k": int, "accuracy": float, "sem": float}`` per prefix scored (with
        ``"log_loss"`` also ``"log_loss"``; ``sem`` is the standard error of the score cut on).
    """
    from sklearn.multiclass import OneVsRestClassifier
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import SVC

    if scoring not in ("accuracy", "log_loss"):
        raise ValueError(f"scoring must be 'accuracy' or 'log_loss', got {scoring!r}")
    X, y, _, y_idx = _check_Xy(X, y)
    ranking = np.asarray(ranking, dtype=int)
    n_classes = int(y_idx.max()) + 1
    if estimator is None:
        svc = SVC(C=100.0, gamma="scale")
        estimator = make_pipeline(StandardScaler(), OneVsRestClassifier(svc) if scoring == "log_loss" else svc)
    rs = check_random_state(random_state)
    folds = _folds(y_idx, cv, rs.randint(np.iinfo(np.int32).max))
    halves = [_halves(y_idx[te], rs.randint(np.iinfo(np.int32).max)) for _, te in folds]
    sizes = _prefix_sizes(ranking.size)

    def score(k, f):
        train, test = folds[f]
        ytr, yte = y_idx[train], y_idx[test]
        cols = ranking[:k]
        seen = np.unique(ytr)
        if seen.size < 2:  # a category too rare to reach this training fold: it can only say the other
            D = np.zeros((test.size, n_classes))
            D[:, seen[0]] = 1.0
        else:
            model = clone(estimator).fit(X[train][:, cols], ytr)
            if scoring == "accuracy":
                return float(np.mean(model.predict(X[test][:, cols]) == yte)), np.nan
            D = _margins(model, X[test][:, cols], n_classes)
        acc = float(np.mean(D.argmax(axis=1) == yte))
        if scoring == "accuracy":
            return acc, np.nan
        a, b = halves[f]
        return acc, 0.5 * (_temperature_log_loss(D, yte, a, b) + _temperature_log_loss(D, yte, b, a))

    jobs = [(k, f) for k in sizes for f in range(len(folds))]
    if n_jobs in (None, 1):
        scores = [score(*job) for job in jobs]
    else:
        scores = Parallel(n_jobs=n_jobs)(delayed(score)(*job) for job in jobs)
    acc = np.asarray([s[0] for s in scores]).reshape(len(sizes), len(folds))
    loss = np.asarray([s[1] for s in scores]).reshape(len(sizes), len(folds))
    cut = acc if scoring == "accuracy" else -loss
    mean, sem = cut.mean(axis=1), cut.std(axis=1) / np.sqrt(len(folds))
    best = int(np.argmax(mean))
    k = next(s for s, m in zip(sizes, mean) if m >= mean[best] - sem[best])
    path = [{"k": s, "accuracy": float(a), "sem": float(e)} for s, a, e in zip(sizes, acc.mean(axis=1), sem)]
    if scoring == "log_loss":
        for p, l in zip(path, loss.mean(axis=1)):
            p["log_loss"] = float(l)
    return k, path


def _halves(y, seed):
    """Two halves of a held-out fold's rows, each category split between them."""
    rng = np.random.default_rng(seed)
    a, b = [], []
    for c in np.unique(y):
        rows = rng.permutation(np.flatnonzero(y == c))
        a.append(rows[::2])
        b.append(rows[1::2])
    return np.sort(np.concatenate(a)), np.sort(np.concatenate(b))


def forward_selection(X, y, estimator=None, cv=5, max_features=None, groups=None, tol=0.0,
                      random_state=None, n_jobs=None):
    """Greedy forward selection with cross-validation (the thesis's ``sequentialfs``).

    Parameters
    ----------
    X : array-like of shape (n_rows, n_features)
    y : array-like of shape (n_rows,)
    estimator : classifier or None, default=None
        None: 10-nearest-neighbours on standardised features, computed incrementally
        (see the module docstring); a classifier is refitted for every candidate.
    cv : int, default=5
        Stratified folds, the same for every candidate.
    max_features : int or None, default=None
        Stop after this many features (a group counts with all its features).
    groups : array-like of shape (n_features,) or None, default=None
        Group label per feature; a group is added as one unit (see :func:`feature_groups`).
    tol : float, default=0.0
        Keep adding while the accuracy rises by more than this.
    random_state : int, RandomState instance or None, default=None
        Seeds the folds.
    n_jobs : int or None, default=None
        Candidates scored in parallel (joblib threads).

    Returns
    -------
    selected : ndarray of int
        Feature indices in the order they were added.
    ranking : ndarray of int
        All feature indices, best first: the selected ones in order, then the others by the
        accuracy they would have given at the last step.
    path : list of dict
        ``{"features": [...], "accuracy": float}`` per step, starting with no feature.
    """
    X, y, _, y_idx = _check_Xy(X, y)
    evaluator = _evaluator(estimator, X, y_idx, cv, random_state, n_jobs)
    units = _units(groups, X.shape[1])
    limit = X.shape[1] if max_features is None else max_features
    chosen: list[int] = []
    current = evaluator.accuracy(np.empty(0, int))
    path = [{"features": [], "accuracy": current}]
    last_scores = {}
    while len(chosen) < len(units):
        have = np.concatenate([units[u] for u in chosen]) if chosen else np.empty(0, int)
        remaining = [u for u in range(len(units)) if u not in chosen and have.size + units[u].size <= limit]
        if not remaining:
            break
        evaluator.set_base(have)
        scores = _score_changes(evaluator, [units[u] for u in remaining], +1, n_jobs)
        last_scores = dict(zip(remaining, scores))
        best = remaining[int(np.argmax(scores))]
        if last_scores[best] - current <= tol:
            break
        chosen.append(best)
        current = last_scores.pop(best)
        path.append({"features": units[best].tolist(), "accuracy": current})
    rest = sorted((u for u in range(len(units)) if u not in chosen), key=lambda u: (-last_scores.get(u, -np.inf), u))
    selected = np.concatenate([units[u] for u in chosen]).astype(int) if chosen else np.empty(0, int)
    ranking = np.concatenate([units[u] for u in chosen + rest]).astype(int)
    return selected, ranking, path


def backward_elimination(X, y, estimator=None, cv=5, groups=None, tol=0.01, random_state=None, n_jobs=None):
    """Greedy backward elimination with cross-validation (the thesis's Schemata search).

    At every step each remaining unit (feature, or group of features) is removed in turn
    and the subset with the highest cross-validated accuracy is kept. The elimination
    runs to the last unit, which ranks all of them; the *selected* subset is the last one
    whose accuracy stayed within ``tol`` of the best accuracy seen so far.

    Parameters
    ----------
    X : array-like of shape (n_rows, n_features)
    y : array-like of shape (n_rows,)
    estimator : classifier or None, default=None
        None: 10-nearest-neighbours on standardised features, computed incrementally
        (see the module docstring); a classifier is refitted for every candidate.
    cv : int, default=5
    groups : array-like of shape (n_features,) or None, default=None
        Group label per feature; a group is removed as one unit (see :func:`feature_groups`).
    tol : float, default=0.01
        Largest accepted drop of accuracy below the best seen.
    random_state : int, RandomState instance or None, default=None
    n_jobs : int or None, default=None

    Returns
    -------
    selected : ndarray of int
        Feature indices kept, best-ranked first.
    ranking : ndarray of int
        All feature indices, best (removed last) first.
    path : list of dict
        ``{"removed": [...], "accuracy": float}`` per step, starting with all features
        (``removed`` empty) and ending with none.
    """
    X, y, _, y_idx = _check_Xy(X, y)
    evaluator = _evaluator(estimator, X, y_idx, cv, random_state, n_jobs)
    units = _units(groups, X.shape[1])

    def cols(us):
        return np.concatenate([units[u] for u in us]).astype(int) if us else np.empty(0, int)

    remaining = list(range(len(units)))
    best = evaluator.accuracy(cols(remaining))
    path = [{"removed": [], "accuracy": best}]
    removed: list[int] = []
    stopped = None
    while remaining:
        if len(remaining) == 1:
            u, acc = remaining[0], evaluator.accuracy(np.empty(0, int))
        else:
            evaluator.set_base(cols(remaining))
            scores = _score_changes(evaluator, [units[v] for v in remaining], -1, n_jobs)
            i = int(np.argmax(scores))
            u, acc = remaining[i], scores[i]
        if stopped is None and acc < best - tol:
            stopped = list(remaining)
        if stopped is None:
            best = max(best, acc)
        remaining.remove(u)
        removed.append(u)
        path.append({"removed": units[u].tolist(), "accuracy": acc})
    order = removed[::-1]
    kept = stopped if stopped is not None else []
    return cols([u for u in order if u in kept]), cols(order), path


class FeatureRelevance(BaseEstimator):
    """Rank object features by their relevance to a behaviour's effect categories.

    Parameters
    ----------
    method : {"relieff", "forward", "backward"}, default="relieff"
    top : int or None, default=None
        Number of features to select, best first. None: ReliefF keeps the shortest prefix
        of its ranking whose cross-validated accuracy is within one standard error of the
        best prefix (:func:`ranking_prefix`, with ``estimator``, ``cv`` and ``n_jobs``);
        the wrappers select what their stopping rule keeps.
    n_samples : int, default=1000
        ReliefF's ``m``.
    n_neighbors : int, default=10
        ReliefF's ``k``.
    estimator : classifier or None, default=None
        Wrappers' classifier (None: 10-NN on standardised features), and the classifier
        that scores ReliefF's ranking prefixes (None: an RBF SVM, see :func:`ranking_prefix`).
    cv : int, default=5
        Wrappers' stratified folds (ReliefF's prefix choice uses at most 3).
    feature_groups : array-like of shape (n_features,) or None, default=None
        Wrappers move a group of features as one unit (see :func:`feature_groups`).
    tol : float or None, default=None
        Wrappers' tolerance; None is 0.0 for forward and 0.01 for backward.
    max_features : int or None, default=None
        Forward selection stops after this many features.
    n_jobs : int or None, default=None
        Wrappers score candidates in parallel.
    random_state : int, RandomState instance or None, default=None
    scoring : {"accuracy", "log_loss"}, default="accuracy"
        What ReliefF's prefix cut scores (:func:`ranking_prefix`); the wrappers count
        accuracy.
    search_rows : int or None, default=None
        ReliefF's prefix cut cross-validates on a stratified sample of at most this many
        rows (:func:`afford.learn.validation.stratified_sample`); the ranking reads every
        row. None: every row.

    Attributes
    ----------
    scores_ : ndarray of shape (n_features,)
        Higher is more relevant. ReliefF: its weights. Wrappers: ``1 - position / n_units``
        of each feature's unit in the selection order (wrappers rank, they do not weigh).
    ranking_ : ndarray of shape (n_features,)
        Feature indices, most relevant first.
    selected_ : ndarray of int
        Indices of the selected features, most relevant first; never empty (when no
        feature beats the majority vote the best-ranked unit is kept).
    path_ : list of dict
        Wrappers' accuracy after every step; ReliefF's accuracy of every ranking prefix
        scored (empty when ``top`` is given).
    n_features_in_ : int

    Examples
    --------
    >>> import numpy as np
    >>> from learn import FeatureRelevance
    >>> rng = np.random.default_rng(0)
    >>> X = rng.random((300, 5))
    >>> y = (X[:, 3] > 0.5).astype(int)
    >>> FeatureRelevance(top=1, random_state=0).fit(X, y).selected_.tolist()
    [3]
    """

    _parameter_constraints = {
        "method": [StrOptions({"relieff", "forward", "backward"})],
        "top": [Interval(numbers.Integral, 1, None, closed="left"), None],
        "n_samples": [Interval(numbers.Integral, 1, None, closed="left")],
        "n_neighbors": [Interval(numbers.Integral, 1, None, closed="left")],
        "estimator": "no_validation",
        "cv": [Interval(numbers.Integral, 2, None, closed="left")],
        "feature_groups": ["array-like", None],
        "tol": [Interval(numbers.Real, 0, None, closed="left"), None],
        "max_features": [Interval(numbers.Integral, 1, None, closed="left"), None],
        "n_jobs": [numbers.Integral, None],
        "random_state": ["random_state"],
        "scoring": [StrOptions({"accuracy", "log_loss"})],
        "search_rows": [Interval(numbers.Integral, 10, None, closed="left"), None],
    }

    #: Rankings saved before the option existed lack it: their cut saw every row.
    search_rows = None

    def __init__(self, method="relieff", top=None, n_samples=1000, n_neighbors=10, estimator=None, cv=5,
                 feature_groups=None, tol=None, max_features=None, n_jobs=None, random_state=None,
                 scoring="accuracy", search_rows=None):
        self.search_rows = search_rows
        self.method = method
        self.top = top
        self.n_samples = n_samples
        self.n_neighbors = n_neighbors
        self.estimator = estimator
        self.cv = cv
        self.feature_groups = feature_groups
        self.tol = tol
        self.max_features = max_features
        self.n_jobs = n_jobs
        self.random_state = random_state
        self.scoring = scoring

    def fit(self, X, y):
        """Score and rank the features of ``X`` for the categories ``y``.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
            Initial object features (optionally with behaviour parameters).
        y : array-like of shape (n_samples,)
            Effect category of each row (rows of pruned categories removed beforehand).

        Returns
        -------
        self : FeatureRelevance
        """
        self._validate_params()
        X = validate_data(self, X, dtype=np.float64, ensure_all_finite=False)
        d = X.shape[1]
        self.path_ = []
        if np.asarray(y).ndim == 1 and len(y) == X.shape[0] and np.unique(y).size == 1:
            check_finite(X)  # one category: no feature tells anything apart
            self.scores_ = np.zeros(d)
            self.ranking_ = np.arange(d)
            self.selected_ = np.zeros(0, dtype=int)
            return self
        X, y, _, _ = _check_Xy(X, y)
        if self.method == "relieff":
            self.scores_ = relieff(X, y, self.n_samples, self.n_neighbors, self.random_state)
            self.ranking_ = np.argsort(-self.scores_, kind="stable")
            if self.top is None:
                rows = stratified_sample(np.unique(y, return_inverse=True)[1], self.search_rows, self.random_state)
                Xs, ys = (X, y) if rows is None else (X[rows], y[rows])
                k, self.path_ = ranking_prefix(Xs, ys, self.ranking_, self.estimator, min(self.cv, 3),
                                               self.random_state, self.n_jobs, self.scoring)
                self.selected_ = self.ranking_[:k]
            else:
                self.selected_ = self.ranking_[: self.top]
            return self
        if self.method == "forward":
            tol = 0.0 if self.tol is None else self.tol
            selected, ranking, path = forward_selection(
                X, y, self.estimator, self.cv, self.max_features, self.feature_groups, tol, self.random_state, self.n_jobs
            )
        else:
            tol = 0.01 if self.tol is None else self.tol
            selected, ranking, path = backward_elimination(
                X, y, self.estimator, self.cv, self.feature_groups, tol, self.random_state, self.n_jobs
            )
        units = _units(self.feature_groups, d)
        unit_of = np.empty(d, dtype=int)
        for i, cols in enumerate(units):
            unit_of[cols] = i
        position = {}
        for f in ranking:
            position.setdefault(unit_of[f], len(position))
        self.scores_ = np.array([1.0 - position[unit_of[f]] / len(units) for f in range(d)])
        self.ranking_ = ranking
        if self.top is not None:
            self.selected_ = ranking[: self.top]
        else:  # nothing beat the majority vote: keep the best unit rather than nothing
            self.selected_ = selected if selected.size else units[unit_of[ranking[0]]]
        self.path_ = path
        return self

    def transform(self, X):
        """Keep the selected features, in ``selected_`` order.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        X_selected : ndarray of shape (n_samples, len(selected_))
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64, ensure_all_finite=False)
        check_finite(X)
        return X[:, self.selected_]
