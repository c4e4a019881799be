"""The per-behaviour learning steps of chapter 8, run on an :class:`Interactions` set.

Each step is what one command runs (``cluster``, ``select-features``, ``train``), and
each works behaviour by behaviour, as the thesis does:

1. :func:`discover_effects`: effect categories of ``after - before``;
2. :func:`rank_features`: which object features tell those categories apart;
3. :func:`train_predictors`: the relevant features (plus the behaviour's parameters alpha)
   to calibrated probabilities over the categories.

Every behaviour gets its own random state, derived from one seed and the behaviour's index,
so results do not depend on the order behaviours are processed in.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from afford.features import Interactions
from afford.features.errors import DataError
from afford.features.interactions import encode_parameters
from afford.learn.effects import EffectCategories
from afford.learn.predictors import AffordancePredictor
from afford.learn.relevance import FeatureRelevance, feature_groups

__all__ = [
    "MIN_ROWS", "behaviour_rows", "predictor_inputs", "discover_effects", "rank_features", "train_predictors",
    "behaviour_seed", "known_columns", "train_known", "train_members", "parameters_of",
]

#: Fewest interactions of one behaviour worth learning from.
MIN_ROWS = 30


def behaviour_seed(seed: int, b: int) -> int:
    return int(np.random.SeedSequence(entropy=seed, spawn_key=(b,)).generate_state(1)[0])


def behaviour_rows(data: Interactions, b: int, labels: np.ndarray | None = None) -> np.ndarray:
    """Rows of behaviour ``b`` (and, given ``labels``, only those with a kept category)."""
    mask = data.behavior == b
    if labels is not None:
        mask &= labels >= 0
    return np.flatnonzero(mask)


def parameters_of(data: Interactions, b: int) -> list[dict]:
    """Behaviour ``b``'s parameter list (as artefacts store it)."""
    return list(data.behaviors[b].get("parameters", []))


def predictor_inputs(before: np.ndarray, params: np.ndarray, selected: np.ndarray, parameters: list[dict]) -> np.ndarray:
    """The predictor's input: the selected entity features, then the behaviour's parameters
    (periodic ones as sine and cosine, :func:`features.encode_parameters`)."""
    return np.hstack([before[:, selected], encode_parameters(params, parameters)])


def _check_rows(data: Interactions, b: int, rows: np.ndarray, what: str) -> None:
    name = data.behavior_names[b]
    if rows.size == 0:
        raise DataError(f"the data hold no interactions of behaviour {name!r}; explore more before {what}")
    if rows.size < MIN_ROWS:
        raise DataError(f"behaviour {name!r} has only {rows.size} usable interactions; {what} needs at least {MIN_ROWS}")


def k_per_behaviour(k: int | dict | None, names: list[str]) -> dict[str, int | None]:
    """One k-means k per behaviour from ``k``: a number for all, or ``{name: k}`` with
    ``"*"`` for the rest (a behaviour left out of both: None, X-means' own choice)."""
    if not isinstance(k, dict):
        return {n: k for n in names}
    unknown = sorted(set(k) - set(names) - {"*"})
    if unknown:
        raise DataError(f"there is no behaviour {unknown[0]!r} to give a k; the behaviours are {', '.join(names)}")
    return {n: k.get(n, k.get("*")) for n in names}


def discover_effects(data: Interactions, *, method: str = "hierarchical", k_max: int = 5,
                     k: int | dict[str, int] | None = None,
                     prune: str = "frequency", min_fraction: float = 0.03, seed: int = 0,
                     channels: list[str] | None = None,
                     progress: Callable[[int], None] | None = None) -> tuple[dict, np.ndarray]:
    """Effect categories per behaviour; returns ``({name: EffectCategories}, labels)``.

    ``channels``: the effect channels categories are formed by (hierarchical; None: all).

    ``k`` (k-means only): one number for every behaviour, or ``{behaviour: k}`` with ``"*"``
    for the others (chapter 7 used 2 for lift and varied the moves').

    ``labels`` has one entry per row: the row's category within its behaviour, or -1 for a
    row whose category was pruned.
    """
    labels = np.full(len(data), -1, dtype=np.int16)
    models = {}
    ks = k_per_behaviour(k, data.behavior_names)
    for b, name in enumerate(data.behavior_names):
        rows = behaviour_rows(data, b)
        _check_rows(data, b, rows, "clustering")
        X = predictor_inputs(data.before_rows(rows), data.params[rows], np.arange(len(data.schema)), parameters_of(data, b))
        ec = effect_categories(data.schema, data.effects_of(rows), X, b, method=method, k_max=k_max, k=ks[name],
                               prune=prune, min_fraction=min_fraction, seed=seed, channels=channels)
        labels[rows] = ec.labels_
        models[name] = ec
        if progress is not None:
            progress(b + 1)
    return models, labels


def effect_categories(schema, E: np.ndarray, X: np.ndarray, b: int, *, method: str = "hierarchical", k_max: int = 5,
                      k: int | None = None, prune: str = "frequency", min_fraction: float = 0.03, seed: int = 0,
                      channels: list[str] | None = None) -> EffectCategories:
    """Behaviour ``b``'s effect categories, found in the effects ``E`` of some of its rows
    (all of them, or a curious robot's bootstrap) whose predictor inputs are ``X``; ``k``
    is its own k-means k (None: X-means' choice)."""
    ec = EffectCategories(schema=tuple(schema.channels), method=method, k_max=k_max, k=k, prune=prune,
                          min_fraction=min_fraction, channels=None if channels is None else tuple(channels),
                          random_state=behaviour_seed(seed, b))
    return ec.fit(E, X)


def rank_features(data: Interactions, labels: np.ndarray, *, method: str = "relieff", top: int | None = None,
                  seed: int = 0, group_channels: bool = False, kernel: str = "rbf", score: str = "accuracy",
                  search_rows: int | None = None, progress: Callable[[int], None] | None = None) -> dict:
    """Feature relevance per behaviour (on rows with a kept category); ``{name: FeatureRelevance}``.

    ReliefF's ranking is cut where cross-validation of the SVM ``train`` will fit says
    (``kernel``: an RBF machine, a linear one as chapter 5's, or a forest), by its accuracy or, with
    ``score="log_loss"``, by its calibrated probabilities' log loss; on a stratified sample
    of at most ``search_rows`` rows a behaviour, where given."""
    out = {}
    groups = feature_groups(data.schema) if group_channels else None
    _check_some_differ(data, labels, "tell apart")
    for b, name in enumerate(data.behavior_names):
        rows = behaviour_rows(data, b, labels)
        _check_rows(data, b, rows, "feature selection")
        y = labels[rows]
        X = data.before_rows(rows)
        d = X.shape[1]
        params = parameters_of(data, b)
        A = encode_parameters(data.params[rows], params) if params else np.zeros((len(rows), 0))
        g = groups
        if A.shape[1]:  # the parameters are candidates too (fig 9.7), each one unit (sine and cosine together)
            X = np.hstack([X, A])
            if g is not None:
                g = np.concatenate([g, _parameter_units(params, int(g.max()) + 1)])
        fr = FeatureRelevance(method=method, top=top, feature_groups=g, random_state=behaviour_seed(seed, b),
                              estimator=prefix_estimator(kernel) if method == "relieff" else None, scoring=score,
                              search_rows=search_rows)
        out[name] = _split_parameters(fr.fit(X, y), d, params)
        if out[name].selected_.size == 0 and not params:
            # One effect only (nothing to tell apart): the predictor will be certain of it
            # whatever it reads, but it must read something; the first feature serves.
            out[name].selected_ = np.asarray(out[name].ranking_[:1], dtype=int)
        if progress is not None:
            progress(b + 1)
    return out


def _parameter_units(params: list[dict], first: int) -> np.ndarray:
    """A unit label per encoded parameter column: a periodic parameter's sine and cosine share one."""
    return np.concatenate([np.full(2 if p.get("periodic") else 1, first + j) for j, p in enumerate(params)]).astype(int)


def _split_parameters(fr: FeatureRelevance, d: int, params: list[dict]) -> FeatureRelevance:
    """Keep the entity features' part of a relevance fitted on entity features and encoded
    parameters (the predictor is always given the parameters), and record each parameter's
    score and rank among the entity features (``parameter_scores_``: name -> (score, rank),
    rank 1 the most relevant)."""
    fr.parameter_scores_ = {}
    if not params:
        return fr
    if not np.any(fr.scores_):  # one effect only: nothing was ranked, the parameters neither
        fr.selected_ = np.asarray([i for i in fr.selected_ if i < d], dtype=int)
        fr.ranking_ = np.arange(d)
        fr.scores_ = np.asarray(fr.scores_[:d])
        return fr
    units = _parameter_units(params, 0)
    order = [int(i) for i in fr.ranking_]
    for j, p in enumerate(params):
        cols = d + np.flatnonzero(units == j)
        first = min(order.index(int(c)) for c in cols)
        rank = 1 + sum(1 for i in order[:first] if i < d)
        fr.parameter_scores_[str(p.get("name", f"alpha{j}"))] = (float(np.max(fr.scores_[cols])), rank)
    fr.selected_ = np.asarray([i for i in fr.selected_ if i < d], dtype=int)
    fr.ranking_ = np.asarray([i for i in order if i < d], dtype=int)
    fr.scores_ = np.asarray(fr.scores_[:d])
    return fr


def _check_some_differ(data: Interactions, labels: np.ndarray, what: str) -> None:
    """Refuse, in one sentence, data in which no behaviour has two effects to tell apart
    (counting only those of two or more interactions: a lone member cannot be learned from).
    A behaviour that alone always had one effect is learned as certain of it."""
    for b in range(len(data.behavior_names)):
        y = labels[behaviour_rows(data, b, labels)]
        if (np.unique(y, return_counts=True)[1] >= 2).sum() >= 2:
            return
    raise DataError(f"every behaviour has {_one_label(data)} (counting only those of two or more interactions); "
                    f"there is nothing to {what}")


def _one_label(data: Interactions) -> str:
    return ("one effect category only" if data.label_source == "discovered"
            else "one result only (every interaction of it ended the same way)")


def prefix_estimator(kernel: str):
    """The classifier that scores ReliefF's ranking prefixes: None (an RBF SVM, see
    :func:`learn.relevance.ranking_prefix`), or for ``"linear"`` a linear SVM on
    standardised features with C = 0.01, in the middle of the linear grid ``train`` searches
    (on 5000 traverse-body interactions cutting with it rather than the RBF machine took the
    held-out accuracy of the linear predictors from 93.4 to 94.2 %). For ``"forest"``, a
    random forest of 100 trees."""
    if kernel == "forest":
        from sklearn.ensemble import RandomForestClassifier

        return RandomForestClassifier(100, min_samples_leaf=3, random_state=0)
    if kernel != "linear":
        return None
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import LinearSVC

    return make_pipeline(StandardScaler(), LinearSVC(C=0.01, dual=False, max_iter=20000))


def train_known(data: Interactions, labels: np.ndarray, *, seed: int = 0, min_rows: int = 10,
                search_rows: int | None = None) -> dict:
    """Per behaviour, P(the effect is of a kind the categories kept | object, alpha).

    Frequency pruning drops rare effects with their members, so a predictor trained on the
    kept categories has never seen them: for an object whose interactions mostly ended in
    a dropped kind (a held object pushed: it drops, then is dragged), it still answers with
    a kept category, confidently. The planner multiplies its step probabilities by this
    one, so plans through such steps are no longer mistaken for sure ones. Behaviours with
    fewer than ``min_rows`` dropped rows get none (``None``).

    It reads every object feature (:func:`known_columns`), not the ones selected to tell
    the kept categories apart: whether an object is held shows in its height, which those
    need not include (out of fold on 5000 table interactions this cut the log loss on held
    objects from 0.50-0.80 to 0.48-0.64).
    """
    out: dict = {}
    for b, name in enumerate(data.behavior_names):
        rows = behaviour_rows(data, b)
        known = (labels[rows] >= 0).astype(int)
        if min(known.sum(), (1 - known).sum()) < min_rows:
            out[name] = None
            continue
        X = predictor_inputs(data.before_rows(rows), data.params[rows], known_columns(data.schema), parameters_of(data, b))
        out[name] = AffordancePredictor(kernel="rbf", calibration="sigmoid", search_rows=search_rows,
                                        random_state=behaviour_seed(seed, b)).fit(X, known)
    return out


def train_members(data: Interactions, labels: np.ndarray, *, seed: int = 0) -> dict:
    """Per behaviour, each entity's own effect within its category (:class:`MemberEffects`).

    It reads every entity feature (:func:`known_columns`) and the behaviour's parameters:
    how far a push moves an object depends on its width, which the features chosen to tell
    the categories apart need not include. The behaviour's rows of a discarded kind (label
    below 0) go along as the pool an unknown outcome is drawn from. Behaviours without kept
    rows get none (``None``).
    """
    from afford.learn.members import MemberEffects

    out: dict = {}
    cols = known_columns(data.schema)
    for b, name in enumerate(data.behavior_names):
        if behaviour_rows(data, b, labels).size == 0:
            out[name] = None
            continue
        rows = behaviour_rows(data, b)
        params = parameters_of(data, b)
        X = predictor_inputs(data.before_rows(rows), data.params[rows], cols, params)
        groups = [data.schema.channels[i] for i in cols] + ["parameters"] * (X.shape[1] - cols.size)
        out[name] = MemberEffects(groups, data.schema.channels, data.schema.tolerances,
                                  random_state=behaviour_seed(seed, b)).fit(X, data.effects_of(rows), labels[rows])
    return out


def known_columns(schema) -> np.ndarray:
    """The object features P(known) reads: all of them."""
    return np.arange(len(schema))


def train_predictors(data: Interactions, labels: np.ndarray, selected: dict[str, np.ndarray], *,
                     kernel: str = "rbf", folds: int = 3, seed: int = 0, n_jobs: int | None = None,
                     search_rows: int | None = None, progress: Callable[[int], None] | None = None) -> dict:
    """One calibrated predictor per behaviour; ``{name: AffordancePredictor}``.

    ``folds``: the cross-validation that chooses C (and gamma) and reports the accuracy
    (3 at the table; the thesis's chapter 5 reported 5-fold cross-validation).
    ``search_rows``: that search sees a stratified sample of at most this many rows."""
    out = {}
    _check_some_differ(data, labels, "predict")
    for b, name in enumerate(data.behavior_names):
        rows = behaviour_rows(data, b, labels)
        _check_rows(data, b, rows, "training")
        y = labels[rows]
        values, counts = np.unique(y, return_counts=True)
        if (counts >= 2).sum() < 2:  # one effect to speak of (lone members cannot be learned from): certain of it
            rows = rows[np.isin(y, values[counts == counts.max()][:1])]
            y = labels[rows]
        X = predictor_inputs(data.before_rows(rows), data.params[rows], selected[name], parameters_of(data, b))
        out[name] = AffordancePredictor(kernel=kernel, cv=folds, n_jobs=n_jobs, search_rows=search_rows,
                                        random_state=behaviour_seed(seed, b)).fit(X, y)
        if progress is not None:
            progress(b + 1)
    return out
