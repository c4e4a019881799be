"""Affordance predictors: P(effect category | object features, behaviour parameters).

The thesis's ``Predictor^b(f_relevant, alpha) -> E`` (3.3.3) is an SVM per behaviour with an
RBF kernel whose C and gamma come from a cross-validated grid (8.5.3). afford adds
calibrated probabilities over the categories (DESIGN.md 7.3), which planning multiplies
along a plan. ``SVC(probability=True)`` is deprecated in scikit-learn 1.9, so the SVM's
decision values are calibrated by :class:`~sklearn.calibration.CalibratedClassifierCV`
(by default one sigmoid per category, one-versus-rest, renormalised), on the same folds
the grid search used.

Categories with very few members
    Folds are stratified, so a category with ``2 <= count < cv`` members sits in ``count``
    different test folds and in every training fold; the folds where it is absent from the
    test part calibrate it on zero positives, which drives its probability towards Platt's
    prior ``1 / (n_negatives + 2)`` (or 0 for isotonic). A category with a *single* member
    is never put in a test fold (a :class:`~sklearn.model_selection.PredefinedSplit` with
    ``-1``): every fold's SVM knows it, no fold can score it, and its probability stays
    near zero. Nothing crashes and no category disappears from ``classes_``.

Saved models are loaded by :func:`skops.io.load` with :data:`TRUSTED_TYPES`, the
scikit-learn types a fitted predictor holds that skops does not trust by default.
"""

from __future__ import annotations

import numbers
import warnings

import numpy as np
from sklearn.base import BaseEstimator, ClassifierMixin, clone
from sklearn.calibration import CalibratedClassifierCV
from sklearn.ensemble import RandomForestClassifier
from sklearn.exceptions import ConvergenceWarning
from sklearn.model_selection import GridSearchCV, PredefinedSplit, StratifiedKFold
from sklearn.pipeline import Pipeline
from sklearn.preprocessing import StandardScaler
from sklearn.multiclass import OneVsRestClassifier
from sklearn.svm import SVC, LinearSVC
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.multiclass import check_classification_targets
from sklearn.utils.validation import check_is_fitted, validate_data

from afford.features.errors import DataError
from afford.learn.validation import check_finite, stratified_sample

__all__ = ["AffordancePredictor", "TRUSTED_TYPES", "PARTS"]

#: Types in a fitted :class:`AffordancePredictor` that ``skops.io`` does not trust by
#: default; pass them to ``skops.io.load(..., trusted=TRUSTED_TYPES)``. A test dumps fitted
#: predictors (every calibration method) and checks that ``get_untrusted_types`` reports
#: exactly these, together.
TRUSTED_TYPES: list[str] = [
    "afford.learn.predictors.AffordancePredictor",
    "sklearn.calibration._CalibratedClassifier",
    "sklearn.calibration._SigmoidCalibration",
    "sklearn.calibration._TemperatureScaling",
    "sklearn.model_selection._split.PredefinedSplit",
    "afford.learn.predictors._Forest",
]

#: Every class a fitted :class:`AffordancePredictor` is built of, skops's default-trusted
#: ones included: a model file's predictor slot may hold these and nothing else (skops trusts
#: much of scikit-learn by default, which would let another estimator pass as a predictor).
#: A test dumps predictors of every kernel and calibration, binary and multi-class, and
#: checks that they hold no other.
PARTS: frozenset[str] = frozenset({
    "afford.learn.predictors.AffordancePredictor",
    "sklearn.calibration.CalibratedClassifierCV",
    "sklearn.calibration._CalibratedClassifier",
    "sklearn.calibration._SigmoidCalibration",
    "sklearn.calibration._TemperatureScaling",
    "sklearn.isotonic.IsotonicRegression",
    "sklearn.model_selection._split.PredefinedSplit",
    "sklearn.multiclass.OneVsRestClassifier",
    "sklearn.pipeline.Pipeline",
    "sklearn.preprocessing._data.StandardScaler",
    "sklearn.preprocessing._label.LabelBinarizer",
    "sklearn.svm._classes.LinearSVC",
    "sklearn.svm._classes.SVC",
    "afford.learn.predictors._Forest",
    "sklearn.tree._classes.DecisionTreeClassifier",  # the forest's unfitted template; its trees are packed
})

#: Default gamma grid, as multiples of ``1 / n_features`` (the "scale" value on
#: standardised inputs).
_GAMMA_FACTORS = (0.1, 1.0, 10.0)

#: The forest's grid: the fewest rows a leaf may hold (1 grows every tree out; more smooths
#: the votes). Its trees: enough that the votes of two seeds differ by about a point.
FOREST_LEAF_GRID = (1, 3, 10)
FOREST_TREES = 200


class _Forest(RandomForestClassifier):
    """A random forest whose trees grow on every core, vote on one, and are saved packed.

    The trees are the same whatever the threads (each has its own seed), but threads add
    their votes up in whatever order they finish, which changes the last bits of the
    probabilities from run to run; one thread gives the same bits every time.
    :meth:`predict_proba` adds the trees' votes in their order, as scikit-learn's forest does
    on one thread, but without a joblib task per tree: 3-11 ms instead of about 80 ms for one
    row and 200 trees (navigation asks for one row at a time; a test checks the bits are the same).

    Saved (``__getstate__``), the trees are packed into a few arrays: every tree's nodes
    end to end, their values, counts, depths and seeds, and the attributes the trees share
    once. skops writes and audits an object per tree otherwise, and loading 7 forests of
    200 trees took 17 s. ``__setstate__`` rebuilds the trees; nothing in the file runs.
    """

    def predict_proba(self, X):
        check_is_fitted(self)
        X = self._validate_X_predict(X)
        proba = np.zeros((X.shape[0], self.n_classes_))
        for tree in self.estimators_:
            proba += tree.predict_proba(X, check_input=False)
        proba /= len(self.estimators_)
        return proba

    def __getstate__(self):
        state = dict(super().__getstate__())  # Python's object.__getstate__ hands out __dict__ itself
        trees = state.pop("estimators_", None)
        if trees:
            state["packed_trees"] = _pack_trees(trees)
        return state

    def __setstate__(self, state):
        state = dict(state)
        packed = state.pop("packed_trees", None)
        if packed is not None:
            state["estimators_"] = _unpack_trees(packed)
        super().__setstate__(state)


def _pack_trees(trees) -> dict:
    """Fitted decision trees as a few arrays (see :class:`_Forest`)."""
    states = [t.__getstate__() for t in trees]
    shared = {k: v for k, v in states[0].items() if k not in ("tree_", "random_state")}
    for st in states[1:]:
        if st.keys() != states[0].keys() or any(
                not np.array_equal(st[k], v) if isinstance(v, np.ndarray) else st[k] != v for k, v in shared.items()):
            raise ValueError("the trees of one forest differ in more than their seeds and nodes")
    reduced = [st["tree_"].__reduce__() for st in states]
    n_features, n_classes, n_outputs = reduced[0][1]
    return {
        "shared": shared,
        "random_state": np.array([st["random_state"] for st in states], dtype=np.int64),
        "n_features": int(n_features), "n_classes": np.asarray(n_classes, dtype=np.intp), "n_outputs": int(n_outputs),
        "node_count": np.array([r[2]["node_count"] for r in reduced], dtype=np.int64),
        "max_depth": np.array([r[2]["max_depth"] for r in reduced], dtype=np.int64),
        "nodes": np.concatenate([r[2]["nodes"] for r in reduced]),
        "values": np.concatenate([r[2]["values"] for r in reduced]),
    }


def _unpack_trees(packed: dict) -> list:
    """The decision trees :func:`_pack_trees` packed."""
    from sklearn.tree import DecisionTreeClassifier
    from sklearn.tree._tree import Tree

    trees, start = [], 0
    n_classes = np.asarray(packed["n_classes"], dtype=np.intp)
    for seed, count, depth in zip(packed["random_state"], packed["node_count"], packed["max_depth"]):
        stop = start + int(count)
        nodes = packed["nodes"][start:stop]
        # a node pointing outside its tree would send a prediction to read outside memory, and
        # one pointing back up would send it round for ever: scikit-learn adds children after
        # their parent, so a split's children come later in the tree, and a leaf has none
        index = np.arange(len(nodes))
        left, right = nodes["left_child"], nodes["right_child"]
        leaf = left == -1
        if len(nodes) != count or len(packed["values"][start:stop]) != count or not (
                np.all(leaf == (right == -1))
                and np.all(~leaf & (left > index) & (left < count) & (right > index) & (right < count) | leaf)
                and np.all((nodes["feature"] < packed["n_features"]) & ((nodes["feature"] >= 0) | leaf))):
            raise ValueError("a packed tree's nodes point outside the tree or the features, or back up the tree")
        tree = Tree(packed["n_features"], n_classes, packed["n_outputs"])
        tree.__setstate__({"max_depth": int(depth), "node_count": int(count),
                           "nodes": np.ascontiguousarray(nodes),
                           "values": np.ascontiguousarray(packed["values"][start:stop])})
        est = DecisionTreeClassifier.__new__(DecisionTreeClassifier)
        est.__setstate__({**packed["shared"], "random_state": int(seed), "tree_": tree})
        trees.append(est)
        start = stop
    if start != len(packed["nodes"]):
        raise ValueError("the packed trees' node counts do not add up to their nodes")
    return trees


def _short(params: dict) -> dict:
    """Grid parameters without their pipeline prefix: ``{"C": .., "gamma": ..}``."""
    return {k.rsplit("__", 1)[-1]: v for k, v in params.items()}


class AffordancePredictor(ClassifierMixin, BaseEstimator):
    """Calibrated SVM (or random forest) predicting a behaviour's effect category from object features.

    ``Pipeline(StandardScaler, OneVsRestClassifier(SVC))`` with C (and gamma) chosen by a
    stratified, cross-validated grid search on accuracy (by default the smoothest setting
    within one standard error of the best), then ``CalibratedClassifierCV`` on the same
    folds. By
    default the calibrator is fitted on the out-of-fold margins and one SVM is refitted on
    all rows (``ensemble=False``): averaging the probabilities of the fold models instead
    made them under-confident (mean confidence 0.75 at 0.85 accuracy on the table scene).

    There is no ``class_weight``: calibration maps the decision values back to the observed
    category frequencies, so re-weighting the SVM would not change the probabilities'
    meaning, only blur them.

    Parameters
    ----------
    kernel : {"rbf", "linear", "forest"}, default="rbf"
        ``"rbf"``: :class:`~sklearn.svm.SVC` (libsvm, as the thesis). ``"linear"``:
        :class:`~sklearn.svm.LinearSVC` solved in the primal (liblinear, squared hinge),
        which takes milliseconds where libsvm's linear kernel takes seconds at C = 100.
        ``"forest"`` (ours, not the thesis's): a random forest of :data:`FOREST_TREES`
        trees whose smallest leaf (:data:`FOREST_LEAF_GRID`) is chosen by the same
        one-standard-error rule, and whose votes are calibrated, both on out-of-bag votes
        instead of folds (:meth:`_fit_forest`). On the traverse scenes' 3900 grid features it reads
        what a linear machine on a short prefix of ReliefF's ranking does not (the body-size
        map of thesis figure 5.5); it needs no feature selection. ``C_grid`` and
        ``gamma_grid`` are ignored.
    C_grid : tuple of float, default=(0.1, 1.0, 10.0, 100.0, 1000.0)
        With ``choice="one-se"`` the smallest C within one standard error of the best is
        taken, so a grid reaching lower regularises more: a linear machine on the traverse
        scenes' grid features took C = 0.1 from this grid; given 0.001 as well, it took that
        and lost up to 5 points on held-out data.
    gamma_grid : tuple of float or None, default=None
        RBF widths to try. None: ``(0.1, 1, 10) / n_features``. Ignored for ``"linear"``.
    cv : int, default=3
        Folds of the grid search and of the calibration.
    choice : {"one-se", "best"}, default="one-se"
        Which grid setting: the smoothest (smallest gamma, then C) within one standard
        error of the most accurate, or the most accurate. On a planted noisy problem the
        smooth one's probabilities are closer to the truth (a test); on the table scene's
        5000 interactions the two mostly coincide, and where they did not (out of fold),
        "best" gained 0.1-0.7 points of accuracy and 0.006-0.018 of ECE.
    calibration : {"sigmoid", "isotonic", "temperature"}, default="temperature"
        Temperature scaling fits one softmax temperature over the per-category margins;
        on the table scene it gave the lowest calibration error (0.03-0.06 against
        0.06-0.10 for Platt scaling). Platt scaling per category (renormalised) never
        answers exactly 0; isotonic regression is more flexible but can answer 0 (an
        infinite log loss).
    ensemble : bool, default=False
        Passed to ``CalibratedClassifierCV`` (see above).
    search_rows : int or None, default=None
        The grid search cross-validates on a stratified sample of at most this many rows
        (every category keeps at least two members where it has them); the calibration and
        the final machine use every row. None: every row. libsvm's cost grows with the
        square of the rows, so 6000 rows a behaviour (chapter 9's 30 000 interactions) made
        the 15-setting search take the most time by far.
    n_jobs : int or None, default=None
        Grid-search candidates and calibration folds fitted in parallel.
    random_state : int, RandomState instance or None, default=None
        Seeds the folds; the fit is otherwise deterministic.

    Attributes
    ----------
    classes_ : ndarray of shape (n_classes,)
        The categories seen in ``y``, sorted; columns of :meth:`predict_proba`.
    calibrated_ : CalibratedClassifierCV
        The fitted model (its own classes are ``0 .. n_classes - 1``).
    cv_report_ : dict
        ``best_params`` (C, gamma), ``cv_accuracy`` and ``cv_accuracy_std`` of the chosen
        setting (a forest's: its out-of-bag accuracy and that accuracy's binomial standard
        error, with ``validation: "out-of-bag"`` and ``n_splits`` 0), ``grid`` (every setting with its accuracy), ``n_splits``,
        ``class_counts`` and ``singleton_classes`` (categories never used as test rows).
    n_features_in_ : int

    Examples
    --------
    >>> import numpy as np
    >>> from learn import AffordancePredictor
    >>> rng = np.random.default_rng(0)
    >>> X = rng.normal(size=(200, 2))
    >>> y = (X[:, 0] > 0).astype(int)
    >>> model = AffordancePredictor(random_state=0).fit(X, y)
    >>> model.predict_proba([[2.0, 0.0]]).round(1)
    array([[0., 1.]])
    """

    _parameter_constraints = {
        "kernel": [StrOptions({"rbf", "linear", "forest"})],
        "C_grid": ["array-like"],
        "gamma_grid": ["array-like", None],
        "cv": [Interval(numbers.Integral, 2, None, closed="left")],
        "choice": [StrOptions({"one-se", "best"})],
        "calibration": [StrOptions({"sigmoid", "isotonic", "temperature"})],
        "ensemble": ["boolean"],
        "search_rows": [Interval(numbers.Integral, 10, None, closed="left"), None],
        "n_jobs": [numbers.Integral, None],
        "random_state": ["random_state"],
    }

    #: Predictors saved before the option existed lack it: they searched every row.
    search_rows = None

    def __init__(self, kernel="rbf", C_grid=(0.1, 1.0, 10.0, 100.0, 1000.0), gamma_grid=None, cv=3, choice="one-se",
                 calibration="temperature", ensemble=False, search_rows=None, n_jobs=None, random_state=None):
        self.ensemble = ensemble
        self.search_rows = search_rows
        self.kernel = kernel
        self.C_grid = C_grid
        self.gamma_grid = gamma_grid
        self.cv = cv
        self.choice = choice
        self.calibration = calibration
        self.n_jobs = n_jobs
        self.random_state = random_state

    def _folds(self, y_idx: np.ndarray) -> PredefinedSplit:
        """Stratified folds; members of single-member categories stay in every training part."""
        counts = np.bincount(y_idx)
        singleton = counts[y_idx] == 1
        rows = np.flatnonzero(~singleton)
        if rows.size < self.cv:
            raise DataError(
                f"y has {y_idx.size} rows, too few to cross-validate with cv={self.cv}: at least "
                f"{self.cv} rows must belong to categories with two or more members."
            )
        if (counts >= 2).sum() < 2:
            raise DataError(
                f"y has {counts.size} categories but only {(counts >= 2).sum()} of them with two or more members; "
                "a predictor needs two such categories to learn from (explore more)."
            )
        seed = check_random_state(self.random_state).randint(np.iinfo(np.int32).max)
        test_fold = np.full(y_idx.size, -1)
        with warnings.catch_warnings():
            warnings.filterwarnings("ignore", message="The least populated class")
            splitter = StratifiedKFold(self.cv, shuffle=True, random_state=seed)
            for i, (_, test) in enumerate(splitter.split(np.zeros(rows.size), y_idx[rows])):
                test_fold[rows[test]] = i
        return PredefinedSplit(test_fold)

    @staticmethod
    def _simplest_good(results) -> int:
        """Index of the smoothest setting within one standard error of the best accuracy.

        Accuracy is flat over much of the grid on noisy data, and the most accurate
        setting is then often a wiggly one (large gamma, large C) whose decision values
        calibrate poorly. The one-standard-error rule takes the smallest gamma, then the
        smallest C, among the settings the folds cannot tell from the best.
        """
        mean = np.asarray(results["mean_test_score"])
        std = np.asarray(results["std_test_score"])
        top = int(np.argmax(mean))
        n_splits = sum(1 for k in results if k.startswith("split") and k.endswith("_test_score"))
        good = np.flatnonzero(mean >= mean[top] - std[top] / np.sqrt(max(n_splits, 1)))
        key = [(_short(p).get("gamma", 0.0), _short(p)["C"]) for p in results["params"]]
        return int(min(good, key=lambda i: key[i]))

    def fit(self, X, y):
        """Choose C (and gamma), then fit the calibrated SVM.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)
            Relevant object features with the behaviour parameters alpha appended.
        y : array-like of shape (n_samples,)
            Effect category of each row (no pruned rows).

        Returns
        -------
        self : AffordancePredictor
        """
        self._validate_params()
        X, y = validate_data(self, X, y, dtype=np.float64, ensure_all_finite=False)
        check_finite(X)
        check_classification_targets(y)
        self.classes_, y_idx = np.unique(y, return_inverse=True)
        if self.classes_.size < 2:
            # A behaviour that always had the same effect (chapter 9's open-hand on an empty
            # table: nothing happens) predicts that effect, with certainty, whatever it sees.
            self.calibrated_ = None
            self.cv_report_ = {"constant": True, "best_params": {}, "cv_accuracy": 1.0, "cv_accuracy_std": 0.0,
                               "grid": [], "n_splits": 0, "class_counts": {str(self.classes_[0]): int(y_idx.size)},
                               "singleton_classes": []}
            return self
        folds = self._folds(y_idx)
        if self.kernel == "forest":
            return self._fit_forest(X, y_idx, folds)

        if self.kernel == "rbf":
            # One RBF machine per category against the rest: its margin is a continuous
            # score per category, which calibrates into informative probabilities. SVC's
            # own multi-class scores are one-vs-one votes, nearly constant once calibrated.
            svc = OneVsRestClassifier(SVC(kernel="rbf"))
            prefix = "svc__estimator__"
        else:  # liblinear's primal solver: seconds faster than libsvm's linear kernel at large C
            svc = LinearSVC(dual=False, max_iter=20000)
            prefix = "svc__"
        base = Pipeline([("scale", StandardScaler()), ("svc", svc)])
        grid = {prefix + "C": [float(c) for c in self.C_grid]}
        if self.kernel == "rbf":
            gammas = self.gamma_grid
            if gammas is None:
                gammas = [f / X.shape[1] for f in _GAMMA_FACTORS]
            grid[prefix + "gamma"] = [float(g) for g in gammas]
        sample = stratified_sample(y_idx, self.search_rows, self.random_state)
        search_folds = folds if sample is None else self._folds(y_idx[sample])
        search = GridSearchCV(base, grid, scoring="accuracy", cv=search_folds, refit=False, n_jobs=self.n_jobs,
                              error_score="raise")
        with warnings.catch_warnings():
            # liblinear may stop at its iteration limit on thousands of raw grid features; the
            # grid search scores what it reached, and a user cannot act on the warning
            warnings.simplefilter("ignore", ConvergenceWarning)
            search.fit(X if sample is None else X[sample], y_idx if sample is None else y_idx[sample])
        params = search.cv_results_["params"]
        if self.choice == "one-se":
            best = self._simplest_good(search.cv_results_)
        else:
            best = int(np.argmax(search.cv_results_["mean_test_score"]))
        model = clone(base).set_params(**params[best])
        cal_rows = np.arange(y_idx.size)
        cal_folds = folds
        if not self.ensemble:
            # Out-of-fold margins must exist for every calibration row, and a category with
            # one member has none (no machine saw it while it was held out): such a
            # category is left out of the model and always gets probability 0.
            cal_rows = np.flatnonzero(folds.test_fold >= 0)
            cal_folds = PredefinedSplit(folds.test_fold[cal_rows])
        self.calibrated_ = CalibratedClassifierCV(model, method=self.calibration, cv=cal_folds, n_jobs=self.n_jobs,
                                                  ensemble=self.ensemble)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", ConvergenceWarning)
            self.calibrated_.fit(X[cal_rows], y_idx[cal_rows])

        self.cv_report_ = {
            "best_params": {k: float(v) for k, v in _short(params[best]).items()},
            "cv_accuracy": float(search.cv_results_["mean_test_score"][best]),
            "cv_accuracy_std": float(search.cv_results_["std_test_score"][best]),
            "grid": [
                {**{k: float(v) for k, v in _short(p).items()}, "accuracy": float(a)}
                for p, a in zip(params, search.cv_results_["mean_test_score"])
            ],
            "n_splits": int(self.cv),
            "search_rows": int(y_idx.size if sample is None else sample.size),
            **self._counts(y_idx),
        }
        return self

    def _counts(self, y_idx) -> dict:
        counts = np.bincount(y_idx)
        return {"class_counts": {str(c): int(n) for c, n in zip(self.classes_.tolist(), counts)},
                "singleton_classes": [str(c) for c, n in zip(self.classes_.tolist(), counts) if n == 1]}

    def _fit_forest(self, X, y_idx, folds):
        """The forest's leaf size and calibration, from its out-of-bag votes.

        Each tree grows on a bootstrap sample, so every row has about a third of the trees
        that never saw it; their votes are an out-of-sample prediction without folds. One
        forest per leaf size is grown on every row, the leaf is chosen by out-of-bag
        accuracy with the one-standard-error rule (the binomial error of the best), and the
        calibrator is fitted on the chosen forest's out-of-bag votes. Three forests instead
        of the 21 of a 5-fold search and calibration: 62 s instead of 3.5 minutes for the 7
        moves of 5000 traverse-room interactions, where a forest grows on 3900 features.

        Rows of single-member categories stay out of the calibration, as in the SVM's.
        """
        from sklearn.calibration import _fit_calibrator

        seed = check_random_state(self.random_state).randint(np.iinfo(np.int32).max)
        n_classes = self.classes_.size
        fits, accuracy, rows = [], [], []
        for leaf in FOREST_LEAF_GRID:
            # scaling changes no split; it keeps one pipeline shape for every learner
            pipe = Pipeline([("scale", StandardScaler()),
                             ("svc", _Forest(FOREST_TREES, min_samples_leaf=leaf, oob_score=True,
                                             random_state=seed, n_jobs=-1))])
            with warnings.catch_warnings():
                warnings.filterwarnings("ignore", message="Some inputs do not have OOB scores")
                pipe.fit(X, y_idx)
            votes = pipe.named_steps["svc"].oob_decision_function_
            seen = np.isfinite(votes).all(axis=1) & (votes.sum(axis=1) > 0)
            fits.append(pipe)
            rows.append(seen)
            accuracy.append(float(np.mean(np.argmax(votes[seen], axis=1) == y_idx[seen])) if seen.any() else 0.0)
        accuracy = np.asarray(accuracy)
        top = int(np.argmax(accuracy))
        error = float(np.sqrt(accuracy[top] * (1.0 - accuracy[top]) / max(int(rows[top].sum()), 1)))
        good = np.flatnonzero(accuracy >= accuracy[top] - error)
        best = int(max(good, key=lambda i: FOREST_LEAF_GRID[i]))  # the smoothest: the largest leaves
        model = fits[best]
        cal = np.flatnonzero(rows[best] & (folds.test_fold >= 0))
        votes = model.named_steps["svc"].oob_decision_function_[cal]
        if n_classes == 2:
            votes = votes[:, 1:]  # as CalibratedClassifierCV hands a binary problem to its calibrator
        calibrated = _fit_calibrator(model, votes, y_idx[cal], np.arange(n_classes), self.calibration, xp=np)
        self.calibrated_ = CalibratedClassifierCV(model, method=self.calibration, cv=folds, ensemble=False)
        self.calibrated_.classes_ = np.arange(n_classes)
        self.calibrated_.calibrated_classifiers_ = [calibrated]
        self.calibrated_.n_features_in_ = X.shape[1]
        self.cv_report_ = {
            "best_params": {"min_samples_leaf": float(FOREST_LEAF_GRID[best])},
            "cv_accuracy": float(accuracy[best]),
            "cv_accuracy_std": error,
            "validation": "out-of-bag",
            "grid": [{"min_samples_leaf": float(leaf), "accuracy": float(a)}
                     for leaf, a in zip(FOREST_LEAF_GRID, accuracy)],
            "n_splits": 0,
            "search_rows": int(y_idx.size),
            **self._counts(y_idx),
        }
        return self

    def predict_proba(self, X):
        """Calibrated probability of each category.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        proba : ndarray of shape (n_samples, n_classes)
            Columns follow ``classes_``; rows sum to 1.
        """
        check_is_fitted(self)
        X = validate_data(self, X, reset=False, dtype=np.float64, ensure_all_finite=False)
        check_finite(X)
        if self.calibrated_ is None:  # one category only: it is certain
            return np.ones((X.shape[0], 1))
        proba = np.zeros((X.shape[0], self.classes_.size))
        proba[:, self.calibrated_.classes_] = self.calibrated_.predict_proba(X)
        return proba

    def predict(self, X):
        """Most probable category.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_features)

        Returns
        -------
        y : ndarray of shape (n_samples,)
        """
        proba = self.predict_proba(X)
        return self.classes_[np.argmax(proba, axis=1)]


class _Margins(ClassifierMixin, BaseEstimator):
    """The one-vs-rest RBF margins of a fitted ``Pipeline(StandardScaler, OvR(SVC))``, in numpy.

    Numerically the same as the pipeline's ``decision_function`` without scikit-learn's
    per-call validation, which costs milliseconds per call: a planner asks for single
    objects thousands of times.
    """

    def __init__(self, pipeline=None):
        self.pipeline = pipeline

    def fit(self, X=None, y=None):
        scale, ovr = self.pipeline.named_steps["scale"], self.pipeline.named_steps["svc"]
        self.mean_, self.std_ = scale.mean_, scale.scale_
        self.parts_ = [(e.support_vectors_, (e.support_vectors_ ** 2).sum(1), e.dual_coef_[0], e.intercept_[0], float(e.gamma))  # the grid passes gamma as a number
                       for e in ovr.estimators_]
        self.classes_ = ovr.classes_
        # The one-vs-rest machines share most of their support vectors (they are all rows of
        # one training set): with one gamma, the kernel is computed once on their union and
        # each machine reads its own columns of it.
        gammas = {g for *_, g in self.parts_}
        if len(gammas) == 1 and self.parts_:
            union, inverse = np.unique(np.vstack([sv for sv, *_ in self.parts_]), axis=0, return_inverse=True)
            inverse = inverse.reshape(-1)
            bounds = np.cumsum([0] + [sv.shape[0] for sv, *_ in self.parts_])
            self.union_ = (union, (union ** 2).sum(1), gammas.pop())
            self.columns_ = [inverse[bounds[i]:bounds[i + 1]] for i in range(len(self.parts_))]
        else:
            self.union_ = None
        return self

    def decision_function(self, X):
        Z = (np.asarray(X, dtype=np.float64) - self.mean_) / self.std_
        zz = (Z * Z).sum(1)[:, None]
        if getattr(self, "union_", None) is not None:
            sv, sq, g = self.union_
            K = np.exp(-g * np.maximum(zz - 2.0 * Z @ sv.T + sq[None, :], 0.0))
            cols = [K[:, idx] @ coef + b for idx, (_, _, coef, b, _) in zip(self.columns_, self.parts_)]
        else:
            cols = [np.exp(-g * np.maximum(zz - 2.0 * Z @ sv.T + sq[None, :], 0.0)) @ coef + b
                    for sv, sq, coef, b, g in self.parts_]
        D = np.column_stack(cols)
        return D[:, 0] if D.shape[1] == 1 else D


def _calibration(c0, estimator_classes):
    """``margins -> probabilities`` of a fitted sigmoid or temperature calibration, in numpy:
    the arithmetic of scikit-learn's ``_CalibratedClassifier.predict_proba`` (1.9) without its
    per-call validation (None for any other method)."""
    from scipy.special import expit, softmax

    classes = np.asarray(c0.classes)
    n = classes.size
    if c0.method == "sigmoid":
        idx = np.searchsorted(np.sort(classes), np.asarray(estimator_classes))
        if n == 2:
            idx = idx + 1
        ab = [(float(c.a_), float(c.b_)) for c in c0.calibrators]

        def sigmoid(D):
            D = D.reshape(len(D), -1)
            proba = np.zeros((len(D), n))
            for j, (a, b), col in zip(idx, ab, D.T):
                proba[:, j] = expit(-(a * col + b))
            if n == 2:
                proba[:, 0] = 1.0 - proba[:, 1]
            else:
                den = proba.sum(axis=1)[:, None]
                proba = np.divide(proba, den, out=np.full_like(proba, 1.0 / n), where=den != 0)
            proba[(1.0 < proba) & (proba <= 1.0 + 1e-5)] = 1.0
            return proba

        return sigmoid
    if c0.method == "temperature":
        beta = float(c0.calibrators[0].beta_)

        def temperature(D):
            D = np.asarray(D, dtype=np.float64)
            if D.ndim == 1 or D.shape[1] == 1:
                d = D.reshape(-1)
                logits = np.column_stack([-d, d])
            elif np.all((D >= 0) & (D <= 1)) and np.all(np.isclose(D.sum(axis=1), 1.0)):
                logits = np.log(D + 1e-12)  # scikit-learn reads such margins as probabilities
            else:
                logits = D
            proba = softmax(beta * logits, axis=1)
            proba[(1.0 < proba) & (proba <= 1.0 + 1e-5)] = 1.0
            return proba

        return temperature
    return None


def fast_predict_proba(predictor: AffordancePredictor):
    """A function ``X -> predict_proba(X)`` for repeated calls on a few rows at a time.

    For the RBF model it computes the margins in numpy and hands them to the fitted
    calibrator (the same numbers as :meth:`AffordancePredictor.predict_proba`, tested);
    anything else falls back to ``predict_proba``. Inputs are not validated: the caller
    passes finite rows of the right width.
    """
    check_is_fitted(predictor)
    cc = predictor.calibrated_
    if cc is None:  # one category only
        return lambda X: np.ones((len(X), 1))
    pipe = cc.calibrated_classifiers_[0].estimator if not cc.ensemble else None
    if pipe is None or not isinstance(pipe.named_steps.get("svc"), OneVsRestClassifier):
        return predictor.predict_proba
    c0 = cc.calibrated_classifiers_[0]
    margins = _Margins(pipe).fit()
    calibrate = _calibration(c0, margins.classes_)
    if calibrate is None:  # a calibration this does not know: scikit-learn's own
        from sklearn.calibration import _CalibratedClassifier

        calibrate = _CalibratedClassifier(margins, c0.calibrators, classes=c0.classes, method=c0.method).predict_proba
        decide = lambda X: X  # noqa: E731
    else:
        decide = margins.decision_function
    columns = cc.classes_
    n_classes = predictor.classes_.size

    def proba(X):
        out = np.zeros((len(X), n_classes))
        out[:, columns] = calibrate(decide(X))
        return out

    return proba
