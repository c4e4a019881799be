"""Effect categories: group the effects a behaviour created, without labels (thesis 3.3.1).

Hierarchical (chapter 8.4.1, Figure 8.3)
    Lower level: X-means inside each channel separately (visibility, position, shape, ...),
    ``k_max`` clusters at most per channel. Upper level: the Cartesian product of the
    channel categories; an all-channel category is one combination that occurs, e.g.
    ``E = V1 ^ P2 ^ S1``. Then pruning, one of

    ``"frequency"`` (chapter 8)
        channel categories and then product categories holding fewer than
        ``min_fraction`` of all samples are dropped together with their members.
    ``"predictability"`` (chapter 10.4.3, Algorithm 7)
        in each channel, cluster with ``k_max``; train, for every channel category, a
        classifier that tells it from the rest *from the initial object features* ``X``;
        if any category scores below ``predictability_threshold``, cluster again with one
        category fewer, down to a single category (no categorisation of that channel).
        At the upper level the same test drops every product category that cannot be
        told from the rest.

K-means (chapter 7)
    One-level k-means with ``k`` clusters on the whole effect vector, each feature
    standardised. A baseline: its result depends on how features of different units are
    weighed against each other, which is what the hierarchical method avoids.

Prototype of a category = mean effect of its members, in the original units.
"""

from __future__ import annotations

import numbers

import numpy as np
from sklearn.base import BaseEstimator, clone
from sklearn.cluster import KMeans
from sklearn.metrics import balanced_accuracy_score
from sklearn.model_selection import StratifiedKFold, cross_val_predict
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.svm import SVC
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_array, check_is_fitted

from afford.features.errors import DataError
from afford.features.schema import FeatureSchema
from afford.learn.validation import check_finite
from afford.learn.xmeans import XMeans

__all__ = ["EffectCategories", "NoCategoryLeft"]


class NoCategoryLeft(DataError):
    """Pruning left no effect category (the command line words its advice in its options)."""


# Predictability checks train one classifier per candidate category; above this many rows
# they run on a random subsample of this size (stratification is kept by the CV splitter).
_PREDICTABILITY_MAX_ROWS = 2000


def _default_predictability_estimator():
    return make_pipeline(StandardScaler(), SVC(kernel="rbf", C=1.0, gamma="scale", class_weight="balanced"))


def _channels_of(schema, n_features: int) -> list[tuple[str, np.ndarray]]:
    """(channel, column indices) in order of first appearance."""
    if schema is None:
        raise DataError(
            "EffectCategories needs schema= (a FeatureSchema or one channel name per effect column) "
            "to know the channels."
        )
    channels = tuple(schema.channels) if isinstance(schema, FeatureSchema) else tuple(str(c) for c in schema)
    if len(channels) != n_features:
        raise DataError(f"E has {n_features} features, but the schema names {len(channels)}.")
    arr = np.asarray(channels)
    return [(ch, np.flatnonzero(arr == ch)) for ch in dict.fromkeys(channels)]


def _order_by_count(labels: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """Permutation old id -> new id: most members first, ties by centre coordinates."""
    k = centers.shape[0]
    counts = np.bincount(labels[labels >= 0], minlength=k)
    keys = [tuple(-c for c in [counts[i]]) + tuple(np.round(centers[i], 12)) for i in range(k)]
    order = sorted(range(k), key=lambda i: keys[i])
    new_id = np.empty(k, dtype=int)
    new_id[order] = np.arange(k)
    return new_id


def _merge_rare(Z: np.ndarray, labels: np.ndarray, centers: np.ndarray, floor: float) -> tuple[np.ndarray, np.ndarray]:
    """Join clusters of fewer than ``floor`` members whose nearest cluster is also that small.

    X-means may split a rare effect into parts that are each too small to keep (the lifts
    of a grasp into "lifted and moved left" and "lifted and moved right"); frequency
    pruning would then drop the whole effect. Two rare clusters nearer to each other than
    to any other cluster are one rare kind at a coarser grain, so the nearest such pair is
    merged (its centre the mean of its members) until no rare cluster has a rare nearest
    neighbour. A rare cluster nearest a common one is left alone (pruning decides it).
    Returns compacted ``(labels, centers)``.
    """
    labels, centers = labels.copy(), centers.copy()
    alive = np.bincount(labels, minlength=centers.shape[0]) > 0  # an empty cluster joins nothing
    while True:
        counts = np.bincount(labels, minlength=centers.shape[0])
        rare = alive & (counts < floor)
        if rare.sum() < 2:
            break
        d = _sq_distances(centers, centers)
        d[:, ~alive] = np.inf
        np.fill_diagonal(d, np.inf)
        nearest = np.argmin(d, axis=1)
        pairs = [(d[i, nearest[i]], i, nearest[i]) for i in np.flatnonzero(rare) if rare[nearest[i]]]
        if not pairs:
            break
        _, i, j = min(pairs)
        labels[labels == j] = i
        alive[j] = False
        centers[i] = Z[labels == i].mean(axis=0)
    keep = np.flatnonzero(alive)
    remap = np.full(centers.shape[0], -1)
    remap[keep] = np.arange(keep.size)
    return remap[labels], centers[keep]


def _sq_distances(Z: np.ndarray, centers: np.ndarray) -> np.ndarray:
    """Squared Euclidean distances (n, k) of rows to centres."""
    return (Z * Z).sum(1)[:, None] - 2.0 * Z @ centers.T + (centers * centers).sum(1)[None, :]


class EffectCategories(BaseEstimator):
    """Discover effect categories and their prototypes from effect vectors.

    Parameters
    ----------
    schema : FeatureSchema or sequence of str, default=None
        The channel of every effect column. A plain tuple of channel names (e.g.
        ``schema.channels``) keeps a saved model free of afford types. Required for
        ``method="hierarchical"``; with ``"kmeans"`` it is only checked against ``E``.
    method : {"hierarchical", "kmeans"}, default="hierarchical"
    k_max : int, default=5
        Most categories X-means may find in one channel (hierarchical), and the number of
        clusters of ``"kmeans"`` when ``k`` is None.
    k : int or None, default=None
        Number of k-means clusters (``method="kmeans"`` only).
    prune : {"frequency", "predictability"}, default="frequency"
    min_fraction : float, default=0.03
        ``prune="frequency"``: smallest share of all samples a category must hold (3 % in
        the thesis).
    predictability_threshold : float, default=0.75
        ``prune="predictability"``: smallest cross-validated *balanced* accuracy of the
        one-category-versus-the-rest classifier. The thesis accepted categories at 78-91 %
        and rejected them at 64-73 % (Table 10.2), on class-balanced data.
    predictability_estimator : classifier or None, default=None
        The classifier of those checks; None is an RBF SVC with balanced class weights on
        standardised ``X`` (the thesis used SVMs).
    n_opt : int, default=1
        Algorithm 7's ``n_opt``: clusterings tried per ``k_max``; the one whose categories are
        predicted best on average is kept. With ``prune="frequency"`` only one is made.
    cv : int, default=3
        Folds of the predictability checks. A category with fewer members cannot be shown
        predictable and fails the check.
    scaling : {"auto", "channel", "feature"}, default="auto"
        How effect columns are scaled before clustering. ``"channel"`` divides each channel
        by one number (the root of its mean per-feature variance): the features of one
        channel share a unit (metres, histogram mass), so their geometry is kept and a
        position change of 10 cm weighs the same along every axis. ``"feature"``
        standardises every column (what Weka's X-means did, and what the one-level baseline
        needs). ``"auto"``: ``"channel"`` for hierarchical, ``"feature"`` for k-means. X-means
        within a channel does not depend on the channel's overall scale, so ``"channel"``
        only matters for prediction distances, where it gives every channel the same weight.
    channels : sequence of str or None, default=None
        The channels whose changes form categories (``"hierarchical"`` only); None: every
        channel of ``schema``. The others still shape each category's prototype (its
        members' mean effect over every column). Chapter 9's tables 9.1 and 9.2 have
        categories of visibility, position and touch only: there the contact point's
        neighbourhood (borders, patches, normals) changes with any move, and X-means
        splits the rare lifts by it into products too small to keep.
    random_state : int, RandomState instance or None, default=None

    Attributes
    ----------
    labels_ : ndarray of shape (n_samples,)
        Category of each training row, ``-1`` for rows pruned with their category.
    n_categories_ : int
    prototypes_ : ndarray of shape (n_categories_, n_features)
        Mean effect of each category's members, original units.
    counts_ : ndarray of shape (n_categories_,)
        Members per category; ids are ordered by count, largest first, ties by channel codes.
    category_codes_ : ndarray of shape (n_categories_, n_channels)
        The channel category of each all-channel category (one column for ``"kmeans"``).
    channels_ : list of str
        Channels in the order of ``category_codes_``'s columns (``["all"]`` for ``"kmeans"``).
    channel_labels_ : dict of str to ndarray of shape (n_samples,)
        Channel category of each row, ``-1`` where the channel category was pruned
        (hierarchical only; empty for ``"kmeans"``).
    channel_prototypes_ : dict of str to ndarray of shape (k_channel, n_channel_features)
        Mean effect of each channel category's members, original units.
    channel_counts_ : dict of str to ndarray
    channel_k_max_ : dict of str to int
        The ``k_max`` each channel ended with (lowered by predictability pruning).
    predictability_ : dict
        Balanced accuracies of the checks made: ``{"channel": {ch: [...]}, "category": [...]}``
        (empty with frequency pruning).
    scale_ : ndarray of shape (n_features,)
        Divisor applied to each effect column before clustering and prediction.
    centers_ : list of ndarray
        Per channel, the cluster centres of the kept channel categories in scaled units;
        :meth:`predict` uses them.
    columns_ : list of ndarray
        Per channel, its effect columns.
    n_features_in_ : int

    Examples
    --------
    >>> import numpy as np
    >>> from learn import EffectCategories
    >>> rng = np.random.default_rng(0)
    >>> vis = -(rng.random(300) < 0.3).astype(float)
    >>> pos = np.where(vis[:, None] < 0, 0.0, rng.choice([0.0, 0.2], size=(300, 1))) + rng.normal(0, 0.01, (300, 2))
    >>> E = np.column_stack([vis, pos])
    >>> ec = EffectCategories(schema=("visibility", "position", "position"), random_state=0).fit(E)
    >>> ec.n_categories_
    3
    """

    _parameter_constraints = {
        "schema": "no_validation",
        "method": [StrOptions({"hierarchical", "kmeans"})],
        "k_max": [Interval(numbers.Integral, 1, None, closed="left")],
        "k": [Interval(numbers.Integral, 1, None, closed="left"), None],
        "prune": [StrOptions({"frequency", "predictability"})],
        "min_fraction": [Interval(numbers.Real, 0, 1, closed="both")],
        "predictability_threshold": [Interval(numbers.Real, 0, 1, closed="both")],
        "predictability_estimator": "no_validation",
        "n_opt": [Interval(numbers.Integral, 1, None, closed="left")],
        "cv": [Interval(numbers.Integral, 2, None, closed="left")],
        "scaling": [StrOptions({"auto", "channel", "feature"})],
        "channels": ["array-like", None],
        "random_state": ["random_state"],
    }

    def __init__(
        self,
        schema=None,
        method="hierarchical",
        k_max=5,
        k=None,
        prune="frequency",
        min_fraction=0.03,
        predictability_threshold=0.75,
        predictability_estimator=None,
        n_opt=1,
        cv=3,
        scaling="auto",
        channels=None,
        random_state=None,
    ):
        self.schema = schema
        self.method = method
        self.k_max = k_max
        self.k = k
        self.prune = prune
        self.min_fraction = min_fraction
        self.predictability_threshold = predictability_threshold
        self.predictability_estimator = predictability_estimator
        self.n_opt = n_opt
        self.cv = cv
        self.scaling = scaling
        self.channels = channels
        self.random_state = random_state

    # ------------------------------------------------------------------ fitting
    def fit(self, E, X=None):
        """Find the categories of the effects ``E``.

        Parameters
        ----------
        E : array-like of shape (n_samples, n_features)
            Effects ``after - before``, one row per interaction of one behaviour.
        X : array-like of shape (n_samples, n_object_features), default=None
            The initial object features of the same interactions (with the behaviour
            parameters alpha appended, if the predictor will see them). Required for
            ``prune="predictability"``, which asks whether each category can be predicted
            from them; ignored otherwise.

        Returns
        -------
        self : EffectCategories
        """
        self._validate_params()
        E = check_array(E, dtype=np.float64, ensure_all_finite=False, ensure_min_samples=2, input_name="E")
        check_finite(E, "E")
        n, d = E.shape
        self.n_features_in_ = d
        if self.prune == "predictability":
            if X is None:
                raise DataError(
                    "prune='predictability' needs the initial object features: call fit(E, X)."
                )
            X = check_array(X, dtype=np.float64, ensure_all_finite=False, input_name="X")
            check_finite(X, "X")
            if X.shape[0] != n:
                raise DataError(f"X has {X.shape[0]} rows but E has {n}; they must describe the same interactions.")
        if self.method == "kmeans" and self.k is not None and self.k > n:
            raise DataError(f"k={self.k} clusters cannot be found in {n} effects.")
        rng = check_random_state(self.random_state)

        if self.method == "hierarchical":
            groups = _channels_of(self.schema, d)
            if self.channels is not None:
                wanted = [str(c) for c in self.channels]
                known = [name for name, _ in groups]
                unknown = [c for c in wanted if c not in known]
                if unknown or not wanted:
                    raise DataError(f"no channel {', '.join(map(repr, unknown)) or 'given'} to form categories by; "
                                    f"the effects' channels are {', '.join(known)}")
                groups = [(name, cols) for name, cols in groups if name in wanted]
        else:
            if self.schema is not None:
                _channels_of(self.schema, d)
            groups = [("all", np.arange(d))]
        scaling = self.scaling
        if scaling == "auto":
            scaling = "channel" if self.method == "hierarchical" else "feature"
        self.scale_ = self._scales(E, groups, scaling)
        Z = E / self.scale_

        self.predictability_ = {}
        if self.prune == "predictability":
            X_check, rows_check = self._subsample(X, n, rng)
            self.predictability_ = {"channel": {}, "category": []}

        codes, centers, channel_k_max = [], [], {}
        all_centers, all_codes = [], []
        for name, cols in groups:
            Zc = Z[:, cols]
            if self.method == "kmeans":
                k = self.k if self.k is not None else self.k_max
                k = min(k, np.unique(Zc, axis=0).shape[0])
                km = KMeans(n_clusters=k, n_init=10, random_state=self._seed(rng)).fit(Zc)
                lab, cen = km.labels_, km.cluster_centers_
                channel_k_max[name] = k
            elif self.prune == "predictability":
                lab, cen, kk, accs = self._predictable_channel(Zc, X_check, rows_check, rng)
                channel_k_max[name] = kk
                self.predictability_["channel"][name] = accs
            else:
                xm = XMeans(k_max=self.k_max, random_state=self._seed(rng)).fit(Zc)
                lab, cen = xm.labels_, xm.cluster_centers_
                channel_k_max[name] = self.k_max
            if self.prune == "frequency" and self.method == "hierarchical":
                lab, cen = _merge_rare(Zc, lab, cen, self.min_fraction * n)
            new_id = _order_by_count(lab, cen)
            lab = new_id[lab]
            cen = cen[np.argsort(new_id)]
            all_centers.append(cen)
            all_codes.append(np.arange(cen.shape[0]))
            if self.prune == "frequency" and self.method == "hierarchical":
                counts = np.bincount(lab, minlength=cen.shape[0])
                keep = counts >= self.min_fraction * n
                remap = np.full(cen.shape[0], -1)
                remap[keep] = np.arange(keep.sum())
                lab = remap[lab]
                cen = cen[keep]
                all_codes[-1] = remap
            codes.append(lab)
            centers.append(cen)
        codes = np.column_stack(codes)

        # Upper level: the combinations of channel categories that occur.
        valid = (codes >= 0).all(axis=1)
        if valid.any():
            combos, inverse, counts = np.unique(codes[valid], axis=0, return_inverse=True, return_counts=True)
            inverse = inverse.ravel()
        else:
            combos, inverse, counts = np.empty((0, codes.shape[1]), int), np.empty(0, int), np.empty(0, int)
        if self.prune == "frequency":
            keep = counts >= self.min_fraction * n
        else:
            combo_of_row = np.full(n, -1)
            combo_of_row[valid] = inverse
            accs = self._predictability(X_check, combo_of_row[rows_check], range(len(combos)), rng)
            self.predictability_["category"] = [
                {"codes": [int(c) for c in combos[i]], "count": int(counts[i]), "balanced_accuracy": accs[i]}
                for i in range(len(combos))
            ]
            keep = np.array([accs[i] >= self.predictability_threshold for i in range(len(combos))], dtype=bool)
            if len(combos) == 1:  # a single category is trivially told from (no) rest
                keep[:] = True
        kept = np.flatnonzero(keep)
        if kept.size == 0:
            raise NoCategoryLeft(
                "no effect category survived pruning; lower min_fraction or "
                "predictability_threshold, or collect more interactions."
            )
        order = sorted(kept, key=lambda i: (-counts[i], tuple(combos[i])))
        new_id = np.full(len(combos), -1)
        new_id[order] = np.arange(len(order))
        labels = np.full(n, -1)
        labels[valid] = new_id[inverse]

        self.labels_ = labels
        self.n_categories_ = len(order)
        self.category_codes_ = combos[order].astype(int)
        self.counts_ = np.bincount(labels[labels >= 0], minlength=self.n_categories_)
        self.prototypes_ = np.vstack([E[labels == c].mean(axis=0) for c in range(self.n_categories_)])
        self.channels_ = [name for name, _ in groups]
        self.columns_ = [cols for _, cols in groups]
        self.centers_ = centers
        self.all_centers_ = all_centers
        self.all_codes_ = all_codes
        self.channel_k_max_ = channel_k_max
        self.channel_labels_, self.channel_prototypes_, self.channel_counts_ = {}, {}, {}
        if self.method == "hierarchical":
            for j, (name, cols) in enumerate(groups):
                lab = codes[:, j]
                k_ch = centers[j].shape[0]
                self.channel_labels_[name] = lab
                self.channel_counts_[name] = np.bincount(lab[lab >= 0], minlength=k_ch)
                self.channel_prototypes_[name] = np.vstack(
                    [E[lab == c][:, cols].mean(axis=0) for c in range(k_ch)]
                ) if k_ch else np.empty((0, cols.size))
        return self

    @staticmethod
    def _seed(rng) -> int:
        return int(rng.randint(np.iinfo(np.int32).max))

    @staticmethod
    def _scales(E, groups, scaling) -> np.ndarray:
        scale = np.ones(E.shape[1])
        std = E.std(axis=0)
        if scaling == "feature":
            scale = np.where(std > 0, std, 1.0)
        else:
            for _, cols in groups:
                s = float(np.sqrt((std[cols] ** 2).mean()))
                scale[cols] = s if s > 0 else 1.0
        return scale

    def _subsample(self, X, n, rng):
        if n <= _PREDICTABILITY_MAX_ROWS:
            return X, np.arange(n)
        rows = np.sort(rng.choice(n, _PREDICTABILITY_MAX_ROWS, replace=False))
        return X[rows], rows

    def _predictability(self, X, labels, categories, rng) -> dict:
        """Cross-validated balanced accuracy of 'category c versus the rest', per category."""
        estimator = self.predictability_estimator
        if estimator is None:
            estimator = _default_predictability_estimator()
        seed = self._seed(rng)
        categories = list(categories)
        result = {}
        for c in categories:
            yb = labels == c
            if yb.sum() < self.cv or (~yb).sum() < self.cv:
                result[c] = 0.0
                continue
            if len(categories) == 2 and (labels >= 0).all() and categories[0] in result:
                result[c] = result[categories[0]]  # the two one-vs-rest problems are the same
                continue
            splitter = StratifiedKFold(self.cv, shuffle=True, random_state=seed)
            pred = cross_val_predict(clone(estimator), X, yb, cv=splitter)
            result[c] = float(balanced_accuracy_score(yb, pred))
        return result

    def _predictable_channel(self, Zc, X, rows, rng):
        """Algorithm 7 in one channel: lower k_max until every category is predictable."""
        k_max = self.k_max
        while True:
            best = None
            for _ in range(self.n_opt):
                xm = XMeans(k_max=k_max, random_state=self._seed(rng)).fit(Zc)
                if xm.n_clusters_ == 1:
                    best = (np.inf, xm, [])
                    break
                accs = self._predictability(X, xm.labels_[rows], range(xm.n_clusters_), rng)
                accs = [accs[c] for c in range(xm.n_clusters_)]
                mean = float(np.mean(accs))
                if best is None or mean > best[0]:
                    best = (mean, xm, accs)
            _, xm, accs = best
            if xm.n_clusters_ == 1 or min(accs) >= self.predictability_threshold:
                return xm.labels_, xm.cluster_centers_, k_max, accs
            # X-means found fewer than k_max clusters, so k_max - 1 would often find the
            # same ones again: go below what was found.
            k_max = xm.n_clusters_ - 1
            if k_max == 1:
                centre = Zc.mean(axis=0, keepdims=True)
                return np.zeros(Zc.shape[0], dtype=int), centre, 1, []

    # --------------------------------------------------------------- prediction
    def _scaled(self, E) -> np.ndarray:
        """Checked effects, in the scaled units the categories were found in."""
        check_is_fitted(self)
        E = check_array(E, dtype=np.float64, ensure_all_finite=False, input_name="E")
        check_finite(E, "E")
        if E.shape[1] != self.n_features_in_:
            raise DataError(
                f"E has {E.shape[1]} features, but EffectCategories is expecting "
                f"{self.n_features_in_} features as input."
            )
        return E / self.scale_

    def predict(self, E):
        """Assign effects to the nearest kept category.

        The distance to a category is the sum over channels of the squared distance, in
        scaled units, to the centre of the category's channel category. For a training row
        whose category was kept this gives its ``labels_`` entry; an effect from a pruned
        combination goes to the kept category nearest to it.

        Parameters
        ----------
        E : array-like of shape (n_samples, n_features)

        Returns
        -------
        labels : ndarray of shape (n_samples,)
            Category ids in ``0 .. n_categories_ - 1``.
        """
        Z = self._scaled(E)
        total = np.zeros((E.shape[0], self.n_categories_))
        for j, cols in enumerate(self.columns_):
            total += _sq_distances(Z[:, cols], self.centers_[j])[:, self.category_codes_[:, j]]
        return np.argmin(total, axis=1)

    def assign(self, E):
        """The category of each effect as training would have labelled it, or -1.

        Each channel's part goes to its nearest channel cluster, pruned ones included; an
        effect whose channel cluster or whose combination of channel categories was
        pruned gets -1, as its training counterparts did. On the training effects this
        reproduces ``labels_`` (up to ties). Held-out evaluation uses it so that a model
        is scored on the categories it knows, and the rows it was never meant to know
        (the thesis discards rare effects with their members) are counted apart.

        Parameters
        ----------
        E : array-like of shape (n_samples, n_features)

        Returns
        -------
        labels : ndarray of shape (n_samples,)
            Category ids in ``0 .. n_categories_ - 1``, or -1.
        """
        Z = self._scaled(E)
        codes = np.empty((E.shape[0], len(self.columns_)), dtype=int)
        for j, cols in enumerate(self.columns_):
            d = _sq_distances(Z[:, cols], self.all_centers_[j])
            codes[:, j] = np.asarray(self.all_codes_[j])[np.argmin(d, axis=1)]
        lookup = {tuple(int(v) for v in row): i for i, row in enumerate(self.category_codes_)}
        return np.array([lookup.get(tuple(int(v) for v in row), -1) for row in codes], dtype=int)

    def __sklearn_tags__(self):
        tags = super().__sklearn_tags__()
        tags.input_tags.allow_nan = False
        return tags
