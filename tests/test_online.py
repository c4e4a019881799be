"""Curiosity-driven online learning (thesis chapter 6) on planted streams: the informative
candidates lie near a known linear boundary, most lie far from it."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features.errors import DataError
from afford.learn.online import learn_online


def stream(seed: int, n: int):
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 1, (n, 12))
    return X, (X[:, 0] + 0.5 * X[:, 1] > 0.8).astype(int)  # features 2-11 carry nothing


X_TEST, Y_TEST = stream(99, 1000)


def needed(curve: list[dict], target: float) -> int:
    return next((c["interactions"] for c in curve if c["accuracy"] >= target), 10**9)


def test_curiosity_needs_far_fewer_interactions_than_random():
    cost = {s: [] for s in ("random", "margin", "entropy", "committee")}
    for order in range(3):
        X, y = stream(order, 700)
        full = learn_online(X, y, "random", X_test=X_TEST, y_test=Y_TEST, every=5, seed=order)
        target = full.curve[-1]["accuracy"] - 0.01  # within a point of what every candidate teaches
        assert full.n_tried == 700
        for strategy in cost:
            run = full if strategy == "random" else learn_online(X, y, strategy, X_test=X_TEST, y_test=Y_TEST,
                                                                 every=5, seed=order)
            cost[strategy].append(needed(run.curve, target))
    median = {s: float(np.median(v)) for s, v in cost.items()}
    assert median["margin"] <= 0.5 * median["random"], median  # the thesis's tau = 0.5
    assert median["entropy"] <= median["margin"] * 1.25 and median["committee"] < median["random"], median


def test_skipped_candidates_are_never_labelled_and_the_bootstrap_always_is():
    X, y = stream(4, 400)
    asked = []

    def label(i):
        asked.append(i)
        return int(y[i])

    run = learn_online(X, label, "margin", bootstrap=60, tau=0.5, n_features=4, seed=1)
    assert asked == sorted(asked) and sorted(asked) == list(np.flatnonzero(run.tried))
    assert run.tried[:60].all() and 60 < run.n_tried < 400
    # what was skipped lay outside the band; what was tried after the bootstrap, inside it
    later = np.arange(60, 400)
    assert (run.interest[later][run.tried[later]] < 0.5).all()
    assert (run.interest[later][~run.tried[later]] >= 0.5).all()
    # ReliefF on the bootstrap kept the two features the boundary is made of
    assert {0, 1} <= set(run.selected.tolist()) and len(run.selected) == 4


def test_an_entropy_budget_is_kept():
    X, y = stream(5, 600)
    run = learn_online(X, y, "entropy", budget=120, seed=2)
    assert 90 <= run.n_tried <= 120


def test_bad_settings_are_one_sentence():
    X, y = stream(6, 50)
    with pytest.raises(DataError, match="unknown strategy"):
        learn_online(X, y, "greedy")
    with pytest.raises(DataError, match="bootstrap needs between 2 and 50"):
        learn_online(X, y, bootstrap=60)


def planted_effects(seed: int, n: int):
    """Candidates whose effect (2 numbers) falls in one of three places, decided by 2 of 12
    features; the learner is told only the effects, and discovers the categories."""
    rng = np.random.default_rng(seed)
    X = rng.uniform(0, 1, (n, 12))
    category = np.where(X[:, 0] < 0.35, 0, np.where(X[:, 1] < 0.5, 1, 2))
    E = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]])[category] + rng.normal(0, 0.05, (n, 2))
    return X, E, category


def kmeans_categorise(calls: list):
    from sklearn.cluster import KMeans

    def categorise(outcomes, rows):
        calls.append(list(rows))
        km = KMeans(3, n_init=10, random_state=0).fit(np.stack(outcomes))
        return lambda E: km.predict(np.asarray(E, dtype=float).reshape(len(E), -1))

    return categorise


def test_curiosity_over_discovered_categories_beats_random_at_equal_interactions():
    Xt, Et, truth = planted_effects(98, 800)
    gain: dict[str, list] = {"entropy": [], "committee": [], "margin": []}
    for order in range(3):
        X, E, _ = planted_effects(order, 700)
        calls: list = []
        acc = {}
        for strategy, budget in (("random", None), ("entropy", 150), ("committee", None), ("margin", None)):
            run = learn_online(X, E, strategy, bootstrap=25, budget=budget, categorise=kmeans_categorise(calls),
                               X_test=Xt, y_test=list(Et), every=5, seed=order)
            acc[strategy] = [c for c in run.curve if c["interactions"] <= 150][-1]["accuracy"]
            if strategy == "random":
                # what was discovered is the planted structure: each place's effects share a category
                found = run.encode(list(Et))
                assert min(np.mean(found[truth == c] == np.bincount(found[truth == c]).argmax()) for c in range(3)) > 0.95
                assert np.unique(found).size == 3
        # the categories are found once per run, from the bootstrap's effects alone
        assert calls == [list(range(25))] * 4
        for s in gain:
            gain[s].append(acc[s] - acc["random"])
    assert all(np.median(g) > 0 for g in gain.values()), gain


def test_one_discovered_category_leaves_nothing_to_be_curious_about():
    X, E, _ = planted_effects(7, 200)
    one = lambda outcomes, rows: (lambda E: np.zeros(len(E), dtype=int))  # every effect alike
    for strategy in ("margin", "entropy", "committee"):
        run = learn_online(X, E, strategy, bootstrap=25, categorise=one, seed=0)
        assert run.n_tried == 25, strategy  # the bootstrap only: the categories are fixed and there is one
