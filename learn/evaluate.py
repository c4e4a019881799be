"""Evaluation on held-out interactions: accuracy, calibration, and baselines (DESIGN.md 7.4).

Held-out rows may carry a category the predictor never saw (a rare effect that was pruned
from, or absent in, the training data). They are kept and counted as wrong: the predictor
gave them probability 0, which the log loss clips to ``eps`` and the Brier score charges in
full.
"""

from __future__ import annotations

import numpy as np
from sklearn.ensemble import RandomForestClassifier
from sklearn.neighbors import KNeighborsClassifier
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.utils import check_random_state

from afford.features.errors import DataError
from afford.learn.validation import check_finite

__all__ = ["baseline_scores", "evaluate_predictions", "reliability_bins"]


def _plain(v):
    """numpy scalar -> Python scalar, for JSON reports."""
    return v.item() if isinstance(v, np.generic) else v


def evaluate_predictions(y_true, proba, classes, n_bins=10, eps=1e-15) -> dict:
    """Score probabilistic predictions of effect categories.

    Parameters
    ----------
    y_true : array-like of shape (n_samples,)
        True category of each held-out interaction.
    proba : array-like of shape (n_samples, n_classes)
        Predicted probabilities; column ``j`` belongs to ``classes[j]``.
    classes : array-like of shape (n_classes,)
    n_bins : int, default=10
        Equal-width confidence bins of the expected calibration error.
    eps : float, default=1e-15
        Probabilities are clipped to ``[eps, 1]`` in the log loss.

    Returns
    -------
    dict
        ``n_samples``; ``accuracy`` (top class == truth); ``log_loss`` (mean ``-log p(truth)``);
        ``brier`` (mean over rows of the squared error between the one-hot truth and the
        probabilities, summed over classes: 0 is perfect, 2 the worst; a row of an unseen
        category adds 1 for its missing column); ``ece`` (expected calibration error of the
        top-class confidence: bin-size-weighted mean of |accuracy - mean confidence| over the
        bins of :func:`reliability_bins`);
        ``labels`` (known classes, then unseen true labels, in order of appearance) and
        ``confusion_matrix`` (rows: true label, columns: predicted label, over ``labels``);
        ``n_unseen`` (rows whose category is not in ``classes``).

    Examples
    --------
    >>> r = evaluate_predictions([0, 1], [[0.8, 0.2], [0.4, 0.6]], [0, 1])
    >>> round(r["accuracy"], 3), round(r["brier"], 3)
    (1.0, 0.2)
    """
    y_true, proba, classes = _check_predictions(y_true, proba, classes)
    n = y_true.shape[0]
    known, col, top, correct = _top_class(y_true, proba, classes)
    seen = col >= 0

    p_true = np.where(seen, proba[np.arange(n), np.where(seen, col, 0)], 0.0)
    log_loss = float(np.mean(-np.log(np.clip(p_true, eps, 1.0))))
    onehot = np.zeros_like(proba)
    onehot[np.flatnonzero(seen), col[seen]] = 1.0
    brier = float(np.mean(((proba - onehot) ** 2).sum(axis=1) + (~seen)))

    bins = _calibration_bins(proba[np.arange(n), top], correct, n_bins)
    ece = sum(b["count"] / n * abs(b["accuracy"] - b["confidence"]) for b in bins)

    labels = classes.tolist() + [v for v in dict.fromkeys(y_true.tolist()) if v not in known]
    index = {v: i for i, v in enumerate(labels)}
    confusion = np.zeros((len(labels), len(labels)), dtype=int)
    np.add.at(confusion, ([index[v] for v in y_true.tolist()], top), 1)
    return {
        "n_samples": int(n),
        "accuracy": float(correct.mean()),
        "log_loss": log_loss,
        "brier": brier,
        "ece": float(ece),
        "labels": [_plain(v) for v in labels],
        "confusion_matrix": confusion.tolist(),
        "n_unseen": int((~seen).sum()),
    }


def reliability_bins(y_true, proba, classes, n_bins=10) -> list[dict]:
    """The reliability diagram of the top-class confidence, bin by bin.

    Rows are binned by the probability of their most probable class into ``n_bins``
    equal-width bins of [0, 1] (closed on the left; the last bin also holds 1.0), the bins
    :func:`evaluate_predictions` computes its ``ece`` over. A row whose true category is
    not in ``classes`` counts as wrong.

    Parameters
    ----------
    y_true : array-like of shape (n_samples,)
    proba : array-like of shape (n_samples, n_classes)
        Predicted probabilities; column ``j`` belongs to ``classes[j]``.
    classes : array-like of shape (n_classes,)
    n_bins : int, default=10

    Returns
    -------
    list of dict
        One ``{"confidence", "accuracy", "count"}`` per non-empty bin, in increasing
        confidence: the bin's mean top-class probability, the fraction of its rows whose
        top class is the truth, and how many rows fell into it.

    Examples
    --------
    >>> bins = reliability_bins([0, 1, 1], [[0.9, 0.1], [0.95, 0.05], [0.35, 0.65]], [0, 1])
    >>> [(round(b["confidence"], 3), b["accuracy"], b["count"]) for b in bins]
    [(0.65, 1.0, 1), (0.925, 0.5, 2)]
    """
    y_true, proba, classes = _check_predictions(y_true, proba, classes)
    _, _, top, correct = _top_class(y_true, proba, classes)
    return _calibration_bins(proba[np.arange(y_true.shape[0]), top], correct, n_bins)


def _check_predictions(y_true, proba, classes) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    y_true = np.asarray(y_true)
    proba = np.asarray(proba, dtype=np.float64)
    classes = np.asarray(classes)
    if proba.ndim != 2 or proba.shape != (y_true.shape[0], classes.shape[0]):
        raise DataError(
            f"proba must have one row per label and one column per class: got shape {proba.shape} "
            f"for {y_true.shape[0]} labels and {classes.shape[0]} classes."
        )
    if y_true.shape[0] == 0:
        raise DataError("there is nothing to evaluate: y_true is empty.")
    check_finite(proba, "proba")
    return y_true, proba, classes


def _top_class(y_true, proba, classes):
    """Column of each row's truth (-1: unseen), the top column, and whether it is right."""
    known = {c: j for j, c in enumerate(classes.tolist())}
    col = np.array([known.get(v, -1) for v in y_true.tolist()])
    top = np.argmax(proba, axis=1)
    return known, col, top, (col >= 0) & (top == col)


def _calibration_bins(confidence: np.ndarray, correct: np.ndarray, n_bins: int) -> list[dict]:
    if int(n_bins) != n_bins or n_bins < 1:
        raise DataError(f"n_bins must be a positive integer, got {n_bins!r}.")
    n_bins = int(n_bins)
    index = np.clip((confidence * n_bins).astype(int), 0, n_bins - 1)
    out = []
    for b in range(n_bins):
        in_bin = index == b
        if in_bin.any():
            out.append({"confidence": float(confidence[in_bin].mean()),
                        "accuracy": float(correct[in_bin].mean()), "count": int(in_bin.sum())})
    return out


def baseline_scores(X_train, y_train, X_test, y_test, random_state=None) -> dict:
    """Accuracy of simple classifiers on the same features, measured in the same run.

    Parameters
    ----------
    X_train, y_train : training features and categories
    X_test, y_test : held-out features and categories
    random_state : int, RandomState instance or None, default=None
        Seeds the random forest.

    Returns
    -------
    dict
        ``majority`` (always the most frequent training category, ties to the smallest),
        ``knn`` (5 nearest neighbours on standardised features) and ``random_forest``
        (100 trees) test accuracies.
    """
    X_train = np.asarray(X_train, dtype=np.float64)
    X_test = np.asarray(X_test, dtype=np.float64)
    y_train = np.asarray(y_train)
    y_test = np.asarray(y_test)
    check_finite(X_train, "X_train")
    check_finite(X_test, "X_test")
    if X_train.ndim != 2 or X_test.ndim != 2 or X_train.shape[1] != X_test.shape[1]:
        raise DataError(
            f"X_train and X_test must be 2-D with the same number of features: got shapes "
            f"{X_train.shape} and {X_test.shape}."
        )
    if y_train.shape[0] != X_train.shape[0] or y_test.shape[0] != X_test.shape[0]:
        raise DataError("each of X_train and X_test needs one label per row.")
    if y_train.shape[0] == 0 or y_test.shape[0] == 0:
        raise DataError("baselines need training and test rows; one of the sets is empty.")
    values, counts = np.unique(y_train, return_counts=True)
    majority = values[np.argmax(counts)]
    knn = make_pipeline(StandardScaler(), KNeighborsClassifier(n_neighbors=min(5, y_train.shape[0])))
    seed = check_random_state(random_state).randint(np.iinfo(np.int32).max)
    forest = RandomForestClassifier(n_estimators=100, random_state=seed)
    return {
        "majority": float(np.mean(y_test == majority)),
        "knn": float(np.mean(knn.fit(X_train, y_train).predict(X_test) == y_test)),
        "random_forest": float(np.mean(forest.fit(X_train, y_train).predict(X_test) == y_test)),
    }
