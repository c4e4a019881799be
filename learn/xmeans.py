"""X-means: k-means that chooses its own number of clusters by BIC (Pelleg & Moore, 2000).

The thesis clustered each effect channel with Weka's X-means (chapter 8, footnote 2). This
is the same search written on scikit-learn's :class:`~sklearn.cluster.KMeans`:

1. *Improve-Params*: run k-means on all rows from the current centres.
2. *Improve-Structure*: split every cluster in two with a local 2-means and keep the
   children where the Bayesian information criterion of the region prefers them.
3. Repeat until no split is kept or ``k_max`` is reached.
4. Also score a plain k-means for every k in ``[k_min, k_max]`` and answer, among all
   structures visited, the one whose global BIC is highest. The local split test is
   greedy: a region holding three groups may not prefer two clusters to one, and then
   X-means stops too early; the global candidates (at most ``k_max`` cheap fits) guard
   against that.

The BIC is that of the paper: identical spherical Gaussians with one pooled variance,
hard assignments, ``(K - 1) + K * M + 1`` free parameters, with the per-dimension
variance estimate ``sigma^2 = SSE / (M (R - K))`` (the paper's text mixes the total and the
per-dimension variance; this keeps them consistent).

The estimator does not rescale its input: k-means and this BIC assume one Euclidean metric,
so the caller decides what a unit is worth (:class:`learn.EffectCategories` scales each
effect channel). Multiplying all columns by one constant does not change the result.
"""

from __future__ import annotations

import numbers

import numpy as np
from sklearn.base import BaseEstimator, ClusterMixin
from sklearn.cluster import KMeans
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import check_is_fitted, validate_data

from afford.features.errors import DataError
from afford.learn.validation import check_finite

__all__ = ["XMeans", "bic_score"]

# A variance of exactly zero (a cluster of identical rows) makes the Gaussian likelihood
# infinite; it is floored at this fraction of the data's mean per-feature variance, which
# still makes every split into exact duplicates win, as it should.
_VARIANCE_FLOOR = 1e-6


def bic_score(X: np.ndarray, labels: np.ndarray, centers: np.ndarray, variance_floor: float = 0.0) -> float:
    """Bayesian information criterion of a hard spherical-Gaussian clustering.

    Parameters
    ----------
    X : ndarray of shape (n_samples, n_features)
    labels : ndarray of shape (n_samples,)
        Index into ``centers`` of each row.
    centers : ndarray of shape (n_clusters, n_features)
    variance_floor : float, default=0.0
        Lower bound of the pooled per-feature variance.

    Returns
    -------
    float
        ``log-likelihood - p / 2 * log(n_samples)``; higher is better.
    """
    R, M = X.shape
    K = centers.shape[0]
    if R <= K:
        return -np.inf
    counts = np.bincount(labels, minlength=K).astype(float)
    sse = float(((X - centers[labels]) ** 2).sum())
    variance = max(sse / (M * (R - K)), variance_floor)
    if variance <= 0.0:
        return np.inf
    nonzero = counts[counts > 0]
    loglik = (
        float((nonzero * np.log(nonzero / R)).sum())
        - R * M / 2.0 * np.log(2.0 * np.pi * variance)
        - sse / (2.0 * variance)
    )
    n_params = (K - 1) + K * M + 1
    return loglik - n_params / 2.0 * np.log(R)


def _nearest(X: np.ndarray, centers: np.ndarray) -> np.ndarray:
    d = (X * X).sum(1)[:, None] - 2.0 * X @ centers.T + (centers * centers).sum(1)[None, :]
    return np.argmin(d, axis=1)


class XMeans(ClusterMixin, BaseEstimator):
    """K-means with the number of clusters chosen by BIC (X-means).

    Parameters
    ----------
    k_min : int, default=1
        Number of clusters the search starts from.
    k_max : int, default=5
        Largest number of clusters considered. It is lowered to the number of distinct
        rows when there are fewer.
    n_init : int, default=3
        k-means++ restarts for the first k-means and for every local 2-means split.
    max_iter : int, default=300
        Iteration limit of each k-means run.
    random_state : int, RandomState instance or None, default=None
        Seeds every k-means run; a given value gives identical clusters.

    Attributes
    ----------
    cluster_centers_ : ndarray of shape (n_clusters_, n_features)
    labels_ : ndarray of shape (n_samples,)
        Index of the nearest centre of each training row.
    n_clusters_ : int
        Number of clusters of the structure with the best BIC.
    bic_ : float
        Its BIC.
    bic_path_ : list of (int, float)
        Every structure visited, as (number of clusters, BIC).
    n_iter_ : int
        k-means iterations of the chosen structure's last run (1 for a single cluster).
    n_features_in_ : int

    Examples
    --------
    >>> import numpy as np
    >>> from learn import XMeans
    >>> rng = np.random.default_rng(0)
    >>> X = np.concatenate([rng.normal(c, 0.1, size=(50, 2)) for c in (0, 3, 6)])
    >>> XMeans(k_max=6, random_state=0).fit(X).n_clusters_
    3
    """

    _parameter_constraints = {
        "k_min": [Interval(numbers.Integral, 1, None, closed="left")],
        "k_max": [Interval(numbers.Integral, 1, None, closed="left")],
        "n_init": [Interval(numbers.Integral, 1, None, closed="left")],
        "max_iter": [Interval(numbers.Integral, 1, None, closed="left")],
        "random_state": ["random_state"],
    }

    def __init__(self, k_min=1, k_max=5, n_init=3, max_iter=300, random_state=None):
        self.k_min = k_min
        self.k_max = k_max
        self.n_init = n_init
        self.max_iter = max_iter
        self.random_state = random_state

    def _kmeans(self, X, k, init, seed):
        return KMeans(
            n_clusters=k, init=init, n_init=1 if not isinstance(init, str) else self.n_init,
            max_iter=self.max_iter, random_state=seed,
        ).fit(X)

    def fit(self, X, y=None):
        """Search the number of clusters and fit the centres.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
        y : ignored

        Returns
        -------
        self : XMeans
        """
        self._validate_params()
        X = validate_data(self, X, dtype=[np.float64, np.float32], ensure_all_finite=False)
        check_finite(X)
        X = np.asarray(X, dtype=np.float64)
        if self.k_min > self.k_max:
            raise DataError(f"k_min={self.k_min} is larger than k_max={self.k_max}.")
        rng = check_random_state(self.random_state)

        def seed():
            return int(rng.randint(np.iinfo(np.int32).max))

        n_distinct = np.unique(X, axis=0).shape[0]
        k_max = min(self.k_max, n_distinct)
        k = min(self.k_min, k_max)
        floor = _VARIANCE_FLOOR * float(X.var(axis=0).mean())

        if k == 1:
            centers = X.mean(axis=0, keepdims=True)
        else:
            centers = self._kmeans(X, k, "k-means++", seed()).cluster_centers_
        path = []
        best = None
        while True:
            # Improve-Params
            n_iter = 1
            if k > 1:
                km = self._kmeans(X, k, centers, seed())
                centers, n_iter = km.cluster_centers_, km.n_iter_
            labels = _nearest(X, centers)
            score = bic_score(X, labels, centers, floor)
            path.append((k, score))
            if best is None or score > best[0]:
                best = (score, centers, labels, n_iter)
            if k >= k_max:
                break
            # Improve-Structure: a local 2-means in every cluster, kept where BIC agrees
            gains, children = [], []
            for j in range(k):
                Xj = X[labels == j]
                if Xj.shape[0] < 3 or not np.ptp(Xj, axis=0).any():
                    continue
                two = self._kmeans(Xj, 2, "k-means++", seed())
                parent = bic_score(Xj, np.zeros(len(Xj), dtype=int), centers[j : j + 1], floor)
                child = bic_score(Xj, two.labels_, two.cluster_centers_, floor)
                if child > parent:
                    gains.append(child - parent)
                    children.append((j, two.cluster_centers_))
            if not children:
                break
            # Keep the best splits that fit under k_max.
            order = np.argsort(-np.asarray(gains), kind="stable")[: k_max - k]
            split = {children[i][0]: children[i][1] for i in order}
            new = []
            for j in range(k):
                if j in split:
                    new.extend(split[j])
                else:
                    new.append(centers[j])
            centers = np.asarray(new)
            k = centers.shape[0]

        # Global candidates: a plain k-means for every k the search may answer.
        for kk in range(max(self.k_min, 2), k_max + 1):
            km = self._kmeans(X, kk, "k-means++", seed())
            centers = km.cluster_centers_
            labels = _nearest(X, centers)
            score = bic_score(X, labels, centers, floor)
            path.append((kk, score))
            if score > best[0]:
                best = (score, centers, labels, km.n_iter_)

        self.bic_, self.cluster_centers_, self.labels_, self.n_iter_ = best
        self.n_clusters_ = int(self.cluster_centers_.shape[0])
        self.bic_path_ = [(int(a), float(b)) for a, b in path]
        return self

    def predict(self, X):
        """Index of the nearest centre of each row.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        labels : ndarray of shape (n_samples,)
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=[np.float64, np.float32], ensure_all_finite=False)
        check_finite(X)
        return _nearest(np.asarray(X, dtype=np.float64), self.cluster_centers_)
