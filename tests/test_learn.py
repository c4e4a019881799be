"""learn/: effect categories, relevant features, calibrated predictors, evaluation.

Every test plants a structure in synthetic data and asserts that it is found (or refused).
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import skops.io as sio
from sklearn.metrics import adjusted_rand_score
from sklearn.utils.estimator_checks import check_estimator

from afford.features import FeatureSchema
from afford.features.errors import DataError
from afford.learn import (
    TRUSTED_TYPES,
    AffordancePredictor,
    EffectCategories,
    FeatureRelevance,
    XMeans,
    backward_elimination,
    baseline_scores,
    evaluate_predictions,
    feature_groups,
    forward_selection,
    relieff,
)

SCHEMA = FeatureSchema(
    names=("visibility", "x", "y", "z", "h0", "h1", "h2", "h3"),
    channels=("visibility",) + ("position",) * 3 + ("shape",) * 4,
)
POSITION_CENTRES = np.array([[0.0, 0.0, 0.0], [0.12, 0.0, 0.0], [0.0, -0.1, 0.15]])
SHAPE_CENTRES = np.array([[0.0, 0.0, 0.0, 0.0], [0.04, -0.04, 0.04, -0.04]])


def planted_effects(n=1200, seed=0, rare=0.0):
    """Effects with independent planted channel categories: visibility 0/-1 (30 %),
    three position clusters, two shape clusters; optionally a rare far position cluster."""
    rng = np.random.default_rng(seed)
    vis = (rng.random(n) < 0.3).astype(int)
    pos = rng.integers(0, 3, n)
    shp = rng.integers(0, 2, n)
    E = np.column_stack([
        -vis.astype(float),
        POSITION_CENTRES[pos] + rng.normal(0, 0.01, (n, 3)),
        SHAPE_CENTRES[shp] + rng.normal(0, 0.004, (n, 4)),
    ])
    rare_rows = np.empty(0, int)
    if rare:
        rare_rows = rng.choice(n, int(rare * n), replace=False)
        E[rare_rows, 1:4] = np.array([0.5, 0.5, 0.5]) + rng.normal(0, 0.01, (rare_rows.size, 3))
    return E, vis, pos, shp, rare_rows


# ---------------------------------------------------------------------------- X-means
@pytest.mark.parametrize("k", [3, 4])
def test_xmeans_recovers_planted_blobs(k):
    rng = np.random.default_rng(k)
    centres = np.array([[0, 0], [6, 0], [0, 6], [6, 6]])[:k]
    truth = rng.integers(0, k, 400)
    X = centres[truth] + rng.normal(0, 0.7, (400, 2))
    model = XMeans(k_max=8, random_state=0).fit(X)
    assert model.n_clusters_ == k
    assert adjusted_rand_score(truth, model.labels_) == pytest.approx(1.0)
    assert np.array_equal(model.predict(X), model.labels_)


def test_xmeans_single_blob_is_one_cluster():
    X = np.random.default_rng(1).normal(size=(500, 3))
    model = XMeans(k_max=6, random_state=0).fit(X)
    assert model.n_clusters_ == 1
    assert set(model.labels_) == {0}


def test_xmeans_degenerate_inputs():
    same = np.ones((20, 3))
    assert XMeans(k_max=5, random_state=0).fit(same).n_clusters_ == 1
    # three distinct points repeated: k_max above the number of distinct rows
    three = np.repeat(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), 7, axis=0)
    model = XMeans(k_min=1, k_max=10, random_state=0).fit(three)
    assert model.n_clusters_ == 3
    # 0 / -1 visibility effects split exactly
    vis = np.r_[np.zeros(30), -np.ones(10)][:, None]
    model = XMeans(random_state=0).fit(vis)
    assert model.n_clusters_ == 2
    assert adjusted_rand_score(vis[:, 0], model.labels_) == 1.0


def test_xmeans_deterministic_and_refuses_nan():
    X = np.random.default_rng(2).normal(size=(200, 2))
    X[:100] += 5
    a = XMeans(random_state=3).fit(X)
    b = XMeans(random_state=3).fit(X)
    assert np.array_equal(a.labels_, b.labels_) and np.allclose(a.cluster_centers_, b.cluster_centers_)
    X[4, 1] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        XMeans().fit(X)


# ------------------------------------------------------------------ effect categories
def test_hierarchical_recovers_channels_and_product():
    E, vis, pos, shp, _ = planted_effects()
    ec = EffectCategories(schema=SCHEMA, random_state=0).fit(E)
    assert {ch: len(c) for ch, c in ec.channel_counts_.items()} == {"visibility": 2, "position": 3, "shape": 2}
    for ch, truth in (("visibility", vis), ("position", pos), ("shape", shp)):
        assert adjusted_rand_score(truth, ec.channel_labels_[ch]) == 1.0
    assert ec.n_categories_ == 12
    product = vis * 6 + pos * 2 + shp
    assert (ec.labels_ >= 0).all()
    assert adjusted_rand_score(product, ec.labels_) == 1.0
    # ids ordered by count; prototypes are member means in original units
    assert np.all(np.diff(ec.counts_) <= 0)
    assert ec.counts_.sum() == len(E)
    for c in range(ec.n_categories_):
        members = ec.labels_ == c
        assert np.allclose(ec.prototypes_[c], E[members].mean(axis=0))
        row = np.flatnonzero(members)[0]
        expected = np.r_[-vis[row], POSITION_CENTRES[pos[row]], SHAPE_CENTRES[shp[row]]]
        assert np.allclose(ec.prototypes_[c], expected, atol=0.005)
    assert np.array_equal(ec.predict(E), ec.labels_)
    # channel names as a plain tuple work the same
    ec2 = EffectCategories(schema=SCHEMA.channels, random_state=0).fit(E)
    assert np.array_equal(ec2.labels_, ec.labels_)


def test_categories_formed_by_some_channels_ignore_the_others_yet_prototypes_span_all():
    E, vis, pos, shp, _ = planted_effects()
    ec = EffectCategories(schema=SCHEMA, channels=("visibility", "position"), random_state=0).fit(E)
    assert ec.channels_ == ["visibility", "position"]
    assert ec.n_categories_ == 6  # the shape channel's two clusters no longer split them
    assert adjusted_rand_score(vis * 3 + pos, ec.labels_) == 1.0
    for c in range(ec.n_categories_):
        assert np.allclose(ec.prototypes_[c], E[ec.labels_ == c].mean(axis=0))  # shape columns included
    assert np.array_equal(ec.predict(E), ec.labels_) and np.array_equal(ec.assign(E), ec.labels_)
    with pytest.raises(DataError, match="no channel 'colour'"):
        EffectCategories(schema=SCHEMA, channels=("visibility", "colour")).fit(E)


def test_frequency_pruning_drops_rare_category_with_members():
    E, vis, pos, shp, rare = planted_effects(rare=0.01)
    ec = EffectCategories(schema=SCHEMA, prune="frequency", min_fraction=0.03, random_state=0).fit(E)
    assert set(np.flatnonzero(ec.labels_ == -1)) == set(rare)
    assert len(ec.channel_counts_["position"]) == 3  # the rare fourth cluster is gone
    assert ec.n_categories_ == 12
    kept = np.setdiff1d(np.arange(len(E)), rare)
    assert adjusted_rand_score((vis * 6 + pos * 2 + shp)[kept], ec.labels_[kept]) == 1.0
    assert (ec.counts_ >= 0.03 * len(E)).all()
    # a held-out effect from the rare cluster still gets the nearest kept category
    assert ec.predict(E[rare]).min() >= 0


def test_product_categories_under_threshold_are_dropped():
    rng = np.random.default_rng(5)
    n = 1000
    vis = (rng.random(n) < 0.5).astype(int)
    pos = np.where(vis == 1, rng.random(n) < 0.02, rng.integers(0, 2, n)).astype(int)  # V1 ^ P1 is rare
    E = np.column_stack([-vis, np.array([[0.0, 0.0], [0.2, 0.1]])[pos] + rng.normal(0, 0.01, (n, 2))])
    ec = EffectCategories(schema=("visibility", "position", "position"), random_state=0).fit(E)
    rare = (vis == 1) & (pos == 1)
    assert 0 < rare.sum() < 0.03 * n
    assert ec.n_categories_ == 3
    assert (ec.labels_[rare] == -1).all() and (ec.labels_[~rare] >= 0).all()


def test_a_rare_effect_split_in_two_by_x_means_is_kept_whole_and_a_lone_rare_one_dropped():
    """Lifts that end left or right of where they started: two modes of 2 % each, nearer each
    other than anything else. Pruned part by part the effect would vanish; kept whole it is 4 %."""
    rng = np.random.default_rng(3)
    centres = np.array([[0.0, 0.0, 0.0], [0.0, 0.10, 0.50], [0.0, -0.10, 0.50], [-0.6, 0.0, 0.0]])
    sizes = (930, 20, 20, 15)  # still, lifted-left, lifted-right, a lone rare shove
    kind = np.repeat(np.arange(4), sizes)
    E = centres[kind] + rng.normal(0, 0.01, (kind.size, 3))
    ec = EffectCategories(schema=("position",) * 3, k_max=4, random_state=0).fit(E)
    assert ec.n_categories_ == 2
    assert len(set(ec.labels_[(kind == 1) | (kind == 2)])) == 1 and ec.labels_[kind == 1][0] >= 0
    assert (ec.labels_[kind == 3] == -1).all()
    assert ec.prototypes_[1, 2] == pytest.approx(0.50, abs=0.01)  # the lift's mean rise


def test_predictability_collapses_unpredictable_channel():
    rng = np.random.default_rng(0)
    n = 900
    X = rng.random((n, 4))
    vis = (X[:, 1] > 0.75).astype(int)                    # predictable from X
    pos = np.digitize(X[:, 0], [1 / 3, 2 / 3])            # predictable from X
    shp = rng.integers(0, 2, n)                           # random: unpredictable
    E = np.column_stack([
        -vis, POSITION_CENTRES[pos] + rng.normal(0, 0.01, (n, 3)), SHAPE_CENTRES[shp] + rng.normal(0, 0.004, (n, 4)),
    ])
    freq = EffectCategories(schema=SCHEMA, random_state=0).fit(E)
    assert len(freq.channel_counts_["shape"]) == 2  # the clusters are real ...
    ec = EffectCategories(schema=SCHEMA, prune="predictability", random_state=0).fit(E, X)
    assert len(ec.channel_counts_["shape"]) == 1    # ... but cannot be predicted
    assert ec.channel_k_max_["shape"] == 1
    assert len(ec.channel_counts_["visibility"]) == 2 and len(ec.channel_counts_["position"]) == 3
    assert ec.n_categories_ == 6
    assert adjusted_rand_score(vis * 3 + pos, ec.labels_) == 1.0
    assert min(ec.predictability_["channel"]["position"]) >= 0.75


def test_predictability_drops_unpredictable_product():
    rng = np.random.default_rng(1)
    n = 900
    X = rng.random((n, 3))
    pos = (X[:, 0] >= 0.5).astype(int)
    vis = (X[:, 1] > 0.7) & (pos == 0)
    noise = rng.choice(np.flatnonzero(pos == 1), int(0.08 * (pos == 1).sum()), replace=False)
    vis[noise] = True  # V1 ^ P1 happens at random
    E = np.column_stack([-vis.astype(float), np.where(pos[:, None] == 1, 0.15, 0.0) + rng.normal(0, 0.01, (n, 2))])
    ec = EffectCategories(schema=("visibility", "position", "position"), prune="predictability",
                          random_state=0).fit(E, X)
    assert set(np.flatnonzero(ec.labels_ == -1)) == set(noise)
    assert ec.n_categories_ == 3
    dropped = [c for c in ec.predictability_["category"] if c["balanced_accuracy"] < 0.75]
    assert len(dropped) == 1 and dropped[0]["count"] == noise.size


def test_kmeans_baseline_and_errors():
    E, vis, pos, shp, _ = planted_effects(n=600)
    km = EffectCategories(schema=SCHEMA, method="kmeans", k=2, min_fraction=0.0, random_state=0).fit(E)
    assert km.n_categories_ == 2 and set(km.labels_) == {0, 1}
    assert km.channel_labels_ == {}
    assert np.array_equal(km.predict(E), km.labels_)
    with pytest.raises(ValueError, match="fit\\(E, X\\)"):
        EffectCategories(schema=SCHEMA, prune="predictability").fit(E)
    with pytest.raises(ValueError, match="schema"):
        EffectCategories().fit(E)
    with pytest.raises(ValueError, match="E has 8 features, but the schema names 3"):
        EffectCategories(schema=("a", "b", "b")).fit(E)
    bad = E.copy()
    bad[3, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        EffectCategories(schema=SCHEMA).fit(bad)
    ec = EffectCategories(schema=SCHEMA, random_state=0).fit(E)
    with pytest.raises(ValueError, match="E has 3 features, but EffectCategories is expecting 8"):
        ec.predict(E[:, :3])
    again = EffectCategories(schema=SCHEMA, random_state=0).fit(E)
    assert np.array_equal(again.labels_, ec.labels_) and np.array_equal(again.prototypes_, ec.prototypes_)


# ------------------------------------------------------------------------- relevance
def relevance_data(n=600, seed=0):
    rng = np.random.default_rng(seed)
    X = rng.normal(size=(n, 12))
    y = np.zeros(n, int)
    y[X[:, 7] > 0.3] = 1
    y[(X[:, 2] < -0.3) & (y == 0)] = 2
    return X, y


def test_relieff_ranks_planted_features_first():
    X, y = relevance_data()
    w = relieff(X, y, n_samples=300, random_state=0)
    assert set(np.argsort(-w)[:2]) == {2, 7}
    assert w[[2, 7]].min() > 5 * np.abs(np.delete(w, [2, 7])).max()
    fr = FeatureRelevance(random_state=0).fit(X, y)
    assert set(fr.selected_) == {2, 7}
    assert sorted(fr.ranking_) == list(range(12))
    assert np.array_equal(fr.transform(X), X[:, fr.selected_])


def test_relieffs_cut_on_a_sample_scores_that_sample_and_keeps_the_planted_features(monkeypatch):
    import afford.learn.relevance as relevance

    X, y = relevance_data()
    seen = []
    real = relevance.ranking_prefix
    monkeypatch.setattr(relevance, "ranking_prefix", lambda X, y, *a: seen.append(len(y)) or real(X, y, *a))
    fr = FeatureRelevance(random_state=0, search_rows=len(y) // 2).fit(X, y)
    assert seen == [pytest.approx(len(y) // 2, abs=3)]  # the cut saw the sample, about half
    assert set(fr.selected_) == {2, 7}  # and still keeps what matters
    FeatureRelevance(random_state=0, search_rows=10 * len(y)).fit(X, y)
    assert seen[-1] == len(y)  # fewer rows than the sample: every row


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_log_loss_cut_keeps_a_feature_that_makes_a_rare_effect_likelier(seed):
    """Feature 0 makes the rare effect possible (40 % of the time, where x0 > 0.85) but never
    the likeliest: the accuracy cut cannot see it, the log loss cut keeps it."""
    from afford.learn.relevance import ranking_prefix

    rng = np.random.default_rng(seed)
    X = rng.random((1500, 5))
    y = (rng.random(1500) < np.where(X[:, 0] > 0.85, 0.4, 0.0)).astype(int)
    ranking = np.array([1, 0, 2, 3, 4])  # a noise feature ranked first
    k_acc, _ = ranking_prefix(X, y, ranking, random_state=0)
    k_loss, path = ranking_prefix(X, y, ranking, random_state=0, scoring="log_loss")
    assert k_acc == 1
    assert k_loss >= 2
    by_k = {p["k"]: p["log_loss"] for p in path}
    assert by_k[2] < by_k[1] - 0.02  # the feature's gain in log loss is real, not within noise
    with pytest.raises(ValueError, match="scoring"):
        ranking_prefix(X, y, ranking, scoring="auc")


def test_a_forest_cuts_the_ranking_by_its_votes_log_loss():
    """A forest has no margins: the log loss cut reads its votes, and still finds the rare
    effect's feature that a noise feature was ranked above."""
    from afford.learn.affordances import prefix_estimator
    from afford.learn.relevance import ranking_prefix

    rng = np.random.default_rng(0)
    X = rng.random((1500, 5))
    y = (rng.random(1500) < np.where(X[:, 0] > 0.85, 0.4, 0.0)).astype(int)
    k, path = ranking_prefix(X, y, np.array([1, 0, 2, 3, 4]), estimator=prefix_estimator("forest"), random_state=0,
                             scoring="log_loss")
    by_k = {p["k"]: p["log_loss"] for p in path}
    assert k >= 2 and by_k[2] < by_k[1] - 0.02


def test_forward_selection_finds_planted_features():
    X, y = relevance_data()
    selected, ranking, path = forward_selection(X, y, random_state=0)
    assert set(selected[:2]) == {2, 7}
    assert set(ranking[:2]) == {2, 7}
    assert path[2]["accuracy"] > path[0]["accuracy"] + 0.3
    fr = FeatureRelevance(method="forward", top=2, random_state=0).fit(X, y)
    assert set(fr.selected_) == {2, 7}
    assert fr.scores_[[2, 7]].min() > np.delete(fr.scores_, [2, 7]).max()


def test_backward_elimination_keeps_planted_group():
    X, y = relevance_data()
    groups = np.array([0, 0, 1, 2, 3, 3, 3, 4, 5, 5, 5, 5])  # 2 and 7 are single units
    selected, ranking, path = backward_elimination(X, y, groups=groups, random_state=0)
    assert set(ranking[:2]) == {2, 7}
    assert {2, 7} <= set(selected)
    assert path[0]["removed"] == [] and path[-1]["accuracy"] < path[0]["accuracy"] - 0.3
    fr = FeatureRelevance(method="backward", feature_groups=groups, random_state=0).fit(X, y)
    assert set(fr.ranking_[:2]) == {2, 7}


def test_feature_groups_treat_histograms_as_units():
    from afford.features import object_schema

    g = feature_groups(object_schema())
    assert len(set(g)) == 1 + 6 + 2
    schema = object_schema()
    assert len(set(g[schema.channel_indices("shape")])) == 2


def test_relevance_refuses_bad_input():
    X, y = relevance_data(n=40)
    with pytest.raises(ValueError, match="only one class"):
        relieff(X, np.zeros(40))
    with pytest.raises(ValueError, match="too few to cross-validate"):
        forward_selection(X[:6], y[:6], cv=5)
    X[0, 0] = np.inf
    with pytest.raises(ValueError, match="NaN or infinite"):
        FeatureRelevance().fit(X, y)


# ------------------------------------------------------------------------ predictors
def noisy_logistic(n, seed):
    rng = np.random.default_rng(seed)
    x = rng.normal(size=(n, 1))
    p = 1.0 / (1.0 + np.exp(-3.0 * x[:, 0]))
    return x, (rng.random(n) < p).astype(int), p


def test_calibrated_probabilities_match_truth():
    x, y, _ = noisy_logistic(1500, 0)
    model = AffordancePredictor(random_state=0).fit(x, y)
    xt, _, pt = noisy_logistic(2000, 1)
    proba = model.predict_proba(xt)
    assert np.allclose(proba.sum(axis=1), 1.0)
    assert np.abs(proba[:, 1] - pt).mean() < 0.07
    assert 0.7 < model.cv_report_["cv_accuracy"] < 0.9  # the Bayes rate here is about 0.8


def test_a_grid_search_on_a_sample_keeps_every_category_and_still_calibrates_on_every_row():
    x, y, _ = noisy_logistic(3000, 0)
    y = y.copy()
    y[:3] = 7  # a rare category: the sample must keep it (two members at least)
    sampled = AffordancePredictor(random_state=0, search_rows=600).fit(x, y)
    report = sampled.cv_report_
    assert 600 <= report["search_rows"] <= 610  # each category's share, rounded, and the rare one's two
    assert sampled.classes_.tolist() == [0, 1, 7]
    assert AffordancePredictor(random_state=0).fit(x[:300], y[:300]).cv_report_["search_rows"] == 300  # unsampled: all
    xt, _, pt = noisy_logistic(2000, 1)
    # the machine and its calibration saw every row: near the planted truth (0.042-0.043 for
    # four seeds; an unsampled search, 20 times slower, was 0.042 on 1200 rows)
    assert np.abs(sampled.predict_proba(xt)[:, 1] - pt).mean() < 0.06
    # the same seed, the same sample: the same model
    again = AffordancePredictor(random_state=0, search_rows=600).fit(x, y)
    assert np.array_equal(again.predict_proba(xt), sampled.predict_proba(xt))


def test_a_predictor_saved_before_search_rows_existed_still_clones_and_an_unsampled_fit_draws_nothing():
    from sklearn.base import clone

    from afford.learn.validation import stratified_sample

    x, y, _ = noisy_logistic(300, 0)
    old = AffordancePredictor(random_state=0).fit(x, y)
    del old.search_rows  # as a predictor written before the option has no such attribute
    assert old.get_params()["search_rows"] is None and clone(old).search_rows is None
    rs = np.random.RandomState(0)
    before = rs.get_state()[1].copy()
    assert stratified_sample(y, None, rs) is None
    assert stratified_sample(y, 10 * len(y), rs) is None
    assert np.array_equal(rs.get_state()[1], before)  # a shared generator moves as it did before


def test_predictor_copes_with_tiny_categories():
    rng = np.random.default_rng(3)
    X = rng.normal(size=(300, 3))
    y = (X[:, 0] > 0).astype(int)
    y[:2] = 5   # two members
    y[2] = 9    # one member
    model = AffordancePredictor(random_state=0).fit(X, y)
    assert model.classes_.tolist() == [0, 1, 5, 9]
    proba = model.predict_proba(X)
    assert proba.shape == (300, 4) and np.allclose(proba.sum(axis=1), 1.0)
    assert proba[:, 3].max() < 0.1
    assert model.cv_report_["singleton_classes"] == ["9"]
    assert (model.predict(X[3:]) == y[3:]).mean() > 0.9


def test_a_behaviour_that_always_had_one_effect_is_certain_of_it():
    """Chapter 9's open-hand on an empty table: nothing ever happens, and the robot learns so."""
    X = np.random.default_rng(0).normal(size=(50, 4))
    model = AffordancePredictor().fit(X, np.full(50, 3))
    assert model.classes_.tolist() == [3] and model.cv_report_["constant"]
    Xt = np.random.default_rng(1).normal(size=(7, 4)) * 10
    assert np.array_equal(model.predict_proba(Xt), np.ones((7, 1))) and model.predict(Xt).tolist() == [3] * 7
    from afford.learn.predictors import fast_predict_proba

    assert np.array_equal(fast_predict_proba(model)(Xt), np.ones((7, 1)))
    fr = FeatureRelevance().fit(X, np.zeros(50))
    assert fr.selected_.size == 0 and np.all(fr.scores_ == 0)


def test_predictor_refuses_bad_input():
    X = np.random.default_rng(0).normal(size=(50, 4))
    bad = X.copy()
    bad[7, 2] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        AffordancePredictor().fit(bad, np.arange(50) % 2)
    with pytest.raises(ValueError, match="too few to cross-validate"):
        AffordancePredictor(cv=3).fit(X[:4], [0, 1, 2, 2])
    model = AffordancePredictor(C_grid=(1.0,), random_state=0).fit(X, np.arange(50) % 2)
    with pytest.raises(ValueError, match="X has 3 features, but AffordancePredictor is expecting 4"):
        model.predict(X[:, :3])
    with pytest.raises(ValueError, match="NaN"):
        model.predict_proba(bad)


def test_predictor_round_trips_through_skops():
    rng = np.random.default_rng(4)
    X = rng.normal(size=(200, 3))
    y = np.digitize(X[:, 0], [-0.5, 0.5])
    reported = set()
    for calibration, kernel in (("sigmoid", "rbf"), ("isotonic", "rbf"), ("temperature", "linear"),
                                ("temperature", "forest")):
        model = AffordancePredictor(kernel=kernel, calibration=calibration, random_state=0).fit(X, y)
        data = sio.dumps(model)
        untrusted = sio.get_untrusted_types(data=data)
        reported |= set(untrusted)
        loaded = sio.loads(data, trusted=TRUSTED_TYPES)
        assert np.array_equal(loaded.predict_proba(X), model.predict_proba(X))
        assert loaded.cv_report_ == model.cv_report_
        if calibration == "sigmoid":  # the SVM needs all but the temperature and the forest
            assert set(TRUSTED_TYPES) - set(untrusted) == {"sklearn.calibration._TemperatureScaling",
                                                           "afford.learn.predictors._Forest"}
    assert reported == set(TRUSTED_TYPES)
    # every class a predictor is built of is in PARTS, the model file's allow-list: binary too
    from afford.artifacts import _check_parts
    from afford.learn.predictors import PARTS

    for calibration, kernel, yy in (("sigmoid", "rbf", y), ("isotonic", "linear", y), ("temperature", "rbf", y > 0),
                                    ("temperature", "linear", y > 0), ("sigmoid", "linear", y > 0),
                                    ("temperature", "forest", y), ("temperature", "forest", y > 0)):
        blob = sio.dumps(AffordancePredictor(kernel=kernel, calibration=calibration, random_state=0).fit(X, yy))
        _check_parts(blob, "fitted", PARTS, "AffordancePredictor")  # raises on a class outside
    with pytest.raises(Exception, match="[Uu]ntrusted"):
        sio.loads(data, trusted=[])


def test_forest_predictor_learns_what_a_linear_machine_cannot_and_repeats_itself():
    # a planted exclusive-or of two signs: no line separates it, trees do
    rng = np.random.default_rng(3)
    X = rng.normal(size=(400, 4))
    y = ((X[:, 0] > 0) ^ (X[:, 1] > 0)).astype(int)
    T = rng.normal(size=(1000, 4))
    truth = ((T[:, 0] > 0) ^ (T[:, 1] > 0)).astype(int)
    forest = AffordancePredictor(kernel="forest", random_state=5).fit(X, y)
    linear = AffordancePredictor(kernel="linear", random_state=5).fit(X, y)
    assert np.mean(forest.predict(T) == truth) > 0.9
    assert np.mean(linear.predict(T) == truth) < 0.65
    p = forest.predict_proba(T)
    assert np.allclose(p.sum(axis=1), 1.0) and "min_samples_leaf" in forest.cv_report_["best_params"]
    # sure where the sign pattern is clear, unsure on the dividing lines
    clear = (np.abs(T[:, 0]) > 1) & (np.abs(T[:, 1]) > 1)
    assert p[clear].max(axis=1).mean() > p[~clear].max(axis=1).mean()
    again = AffordancePredictor(kernel="forest", random_state=5, n_jobs=1).fit(X, y)
    assert np.array_equal(again.predict_proba(T), p)  # the same trees whatever the threads
    from afford.artifacts import dump_estimator

    twin = AffordancePredictor(kernel="forest", random_state=5).fit(X, y)
    assert dump_estimator(twin) == dump_estimator(forest)  # and the same bytes in a model file


def test_predictor_is_deterministic():
    X, y = relevance_data(n=300)
    a = AffordancePredictor(random_state=7).fit(X, y).predict_proba(X)
    b = AffordancePredictor(random_state=7).fit(X, y).predict_proba(X)
    assert np.array_equal(a, b)


# --------------------------------------------------------------- scikit-learn checks
# Checks that skip themselves for reasons of this environment, not of the estimator.
ENVIRONMENT_SKIPS = ("pandas is not installed", "SCIPY_ARRAY_API is not set")


@pytest.mark.parametrize(
    "estimator",
    [XMeans(random_state=0), AffordancePredictor(C_grid=(1.0, 10.0), gamma_grid=(0.5,), random_state=0)],
    ids=["XMeans", "AffordancePredictor"],
)
def test_scikit_learn_estimator_checks(estimator):
    results = []

    def record(estimator, check_name, exception, status, expected_to_fail, expected_to_fail_reason):
        results.append((check_name, status, exception))

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        check_estimator(estimator, on_fail=None, on_skip=None, callback=record)
    failed = [(name, repr(exc)) for name, status, exc in results if status == "failed"]
    assert failed == []
    odd_skips = [(name, str(exc)) for name, status, exc in results
                 if status == "skipped" and not any(s in str(exc) for s in ENVIRONMENT_SKIPS)]
    assert odd_skips == []
    assert sum(status == "passed" for _, status, _ in results) > 40


# ------------------------------------------------------------------------ evaluation
def test_evaluate_predictions_by_hand():
    proba = [[0.9, 0.1], [0.3, 0.7], [0.6, 0.4], [0.5, 0.5]]
    r = evaluate_predictions([0, 1, 1, 7], proba, classes=[0, 1])
    assert r["accuracy"] == 0.5  # the unseen category 7 counts as wrong
    assert r["log_loss"] == pytest.approx(-(np.log(0.9) + np.log(0.7) + np.log(0.4) + np.log(1e-15)) / 4)
    assert r["brier"] == pytest.approx((0.02 + 0.18 + 0.72 + 1.5) / 4)
    assert r["ece"] == pytest.approx((0.1 + 0.3 + 0.6 + 0.5) / 4)
    assert r["labels"] == [0, 1, 7]
    assert r["confusion_matrix"] == [[1, 0, 0], [1, 1, 0], [1, 0, 0]]
    assert r["n_unseen"] == 1
    perfect = evaluate_predictions(["a", "b"], [[1.0, 0.0], [0.0, 1.0]], ["a", "b"])
    assert perfect["accuracy"] == 1.0 and perfect["brier"] == 0.0 and perfect["ece"] == 0.0
    with pytest.raises(ValueError, match="one column per class"):
        evaluate_predictions([0, 1], [[1.0], [0.0]], [0, 1])


def test_baseline_scores():
    Xtr = np.array([[0.0], [0.1], [0.2], [1.0], [1.1], [1.2], [1.3]])
    ytr = np.array([0, 0, 0, 1, 1, 1, 1])
    Xte = np.array([[0.05], [1.15], [1.25]])
    yte = np.array([0, 1, 3])
    s = baseline_scores(Xtr, ytr, Xte, yte, random_state=0)
    assert s["majority"] == pytest.approx(1 / 3)
    assert s["knn"] == pytest.approx(2 / 3) and s["random_forest"] == pytest.approx(2 / 3)


@pytest.mark.parametrize("kernel", ["rbf", "linear"])
def test_fast_probabilities_equal_predict_proba(kernel):
    from afford.learn.predictors import fast_predict_proba

    rng = np.random.default_rng(5)
    X = rng.normal(size=(240, 4))
    y = (X[:, 0] > 0).astype(int) + (X[:, 1] > 0.5)
    y[:1] = 7  # a single-member category: left out of the calibrated model
    model = AffordancePredictor(kernel=kernel, random_state=0).fit(X, y)
    fast = fast_predict_proba(model)
    Xt = rng.normal(size=(30, 4))
    assert np.allclose(fast(Xt), model.predict_proba(Xt), atol=1e-9)
    for calibration in ("sigmoid", "temperature"):
        binary = AffordancePredictor(calibration=calibration, random_state=0).fit(X, (X[:, 2] > 0).astype(int))
        assert np.allclose(fast_predict_proba(binary)(Xt), binary.predict_proba(Xt), atol=1e-9)
    multi = AffordancePredictor(calibration="sigmoid", random_state=0).fit(X, y)
    assert np.allclose(fast_predict_proba(multi)(Xt), multi.predict_proba(Xt), atol=1e-9)


def test_grid_choice_best_or_smoothest_within_one_standard_error():
    x, y, _ = noisy_logistic(600, 3)
    best = AffordancePredictor(choice="best", random_state=0).fit(x, y).cv_report_
    smooth = AffordancePredictor(choice="one-se", random_state=0).fit(x, y).cv_report_
    assert best["cv_accuracy"] == max(g["accuracy"] for g in best["grid"])
    assert smooth["cv_accuracy"] >= best["cv_accuracy"] - best["cv_accuracy_std"]
    assert (smooth["best_params"]["gamma"], smooth["best_params"]["C"]) <= (best["best_params"]["gamma"], best["best_params"]["C"])


def test_a_category_with_one_member_is_ranked_around_and_refused_as_the_only_other():
    X = np.random.default_rng(0).random((40, 20))
    y = np.zeros(40, dtype=int)
    y[0] = 1  # one interaction ended otherwise: no training fold of the cut's cross-validation may see it
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler
    from sklearn.svm import LinearSVC

    fr = FeatureRelevance(estimator=make_pipeline(StandardScaler(), LinearSVC(dual=False)), random_state=0).fit(X, y)
    assert fr.selected_.size >= 1
    with pytest.raises(ValueError, match="only 1 of them with two or more members"):
        AffordancePredictor(kernel="linear", cv=5, random_state=0).fit(X, y)


def test_a_wrapper_that_would_run_for_hours_is_announced_and_a_small_one_is_not():
    from afford.api import wrapper_cost
    from afford.features import FeatureSchema

    grid = FeatureSchema(tuple(f"cell_{i}" for i in range(3900)), ("distance",) * 3900)  # chapter 5's range grid
    slow = wrapper_cost(grid, "backward")
    assert slow is not None and "3900 features" in slow and "38,034,750" in slow and "relieff" in slow
    assert "19,500" in wrapper_cost(grid, "forward")
    assert wrapper_cost(grid, "relieff") is None
    table = FeatureSchema(tuple(f"f{i}" for i in range(43)), ("position",) * 43)
    assert wrapper_cost(table, "backward") is None and wrapper_cost(table, "forward") is None


def test_forest_votes_as_scikit_learn_and_is_saved_packed():
    """_Forest adds its trees' votes without a joblib task per tree, to the same bits as
    scikit-learn's forest on one thread; saved, its trees are packed into arrays (no tree
    object in the file) and rebuilt to the same votes and the same canonical bytes."""
    from sklearn.ensemble import RandomForestClassifier

    from afford.artifacts import dump_estimator
    from afford.learn.predictors import _Forest

    rng = np.random.default_rng(8)
    X = rng.normal(size=(300, 6))
    y = np.digitize(X[:, 0] * X[:, 1], [-0.3, 0.3])
    T = rng.normal(size=(200, 6))
    ours = _Forest(50, min_samples_leaf=2, random_state=4, n_jobs=-1).fit(X, y)
    theirs = RandomForestClassifier(50, min_samples_leaf=2, random_state=4, n_jobs=1).fit(X, y)
    assert np.array_equal(ours.predict_proba(T), theirs.predict_proba(T))
    data = sio.dumps(ours)
    assert sio.get_untrusted_types(data=data) == ["afford.learn.predictors._Forest"]  # no tree in the file
    assert len(ours.estimators_) == 50  # saving left the forest whole
    loaded = sio.loads(data, trusted=TRUSTED_TYPES)
    assert len(loaded.estimators_) == 50 and np.array_equal(loaded.predict_proba(T), theirs.predict_proba(T))
    assert dump_estimator(loaded) == dump_estimator(ours)
    # an edited file whose node points outside its tree is refused, not followed
    from afford.learn.predictors import _pack_trees, _unpack_trees

    packed = _pack_trees(ours.estimators_)
    assert len(_unpack_trees(packed)) == 50
    for field, value in (("left_child", 10**6), ("right_child", 0), ("feature", 6)):  # outside; a loop; no feature
        edited = dict(packed, nodes=packed["nodes"].copy())
        edited["nodes"][field][0] = value
        with pytest.raises(ValueError, match="outside"):
            _unpack_trees(edited)


def test_forest_probabilities_are_calibrated_out_of_bag():
    # P(y = 1 | x) = sigmoid(2 x0) planted: out-of-bag votes calibrate the forest to within
    # 4 points per probability decile on fresh rows
    rng = np.random.default_rng(11)

    def draw(n):
        X = rng.normal(size=(n, 5))
        p = 1 / (1 + np.exp(-2.0 * X[:, 0]))
        return X, (rng.random(n) < p).astype(int), p

    X, y, _ = draw(1500)
    T, t, truth = draw(4000)
    model = AffordancePredictor(kernel="forest", random_state=0).fit(X, y)
    assert model.cv_report_["validation"] == "out-of-bag" and 0.7 < model.cv_report_["cv_accuracy"] < 0.8
    p = model.predict_proba(T)[:, 1]
    decile = np.minimum((p * 10).astype(int), 9)
    ece = sum(abs(p[decile == k].mean() - t[decile == k].mean()) * np.mean(decile == k) for k in np.unique(decile))
    assert ece < 0.04 and np.abs(p - truth).mean() < 0.08
