"""Choosing a behaviour's parameter (thesis 9.5): the largest group of alphas per predicted
next state, its circular mean; and the alpha that makes a next state most probable."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features.contact_point import contact_point_schema
from afford.plan.forward import BehaviorModel, ForwardModel, _largest_run, _mean_angle
from afford.plan.goals import parse_goal
from afford.plan.search import best_first

SCHEMA = contact_point_schema()
D = len(SCHEMA)
Z = SCHEMA.index("cp_z")


class Window:
    """P(lifted) is high for approach angles in a window and falls off from its peak."""

    def __init__(self, lo, hi, peak, periodic=True):
        self.classes_ = np.array([0, 1])  # 0 lifted, 1 not lifted
        self.lo, self.hi, self.peak = lo, hi, peak

    def predict_proba(self, X):
        a = np.degrees(np.arctan2(X[:, -2], X[:, -1]))  # alpha from its sine and cosine
        d = (a - self.lo) % 360.0
        inside = d <= (self.hi - self.lo) % 360.0
        off = np.abs(((a - self.peak) + 180.0) % 360.0 - 180.0)
        p = np.where(inside, 0.95 - 0.002 * off, 0.1)
        return np.column_stack([p, 1 - p])


def grasp_model(lo, hi, peak, rng=(-90.0, 90.0), rule="group"):
    lifted = np.zeros(D)
    lifted[Z] = 0.25
    b = BehaviorModel("power-grasp", Window(lo, hi, peak), np.array([Z]), np.stack([lifted, np.zeros(D)]),
                      parameters=[rng], periodic=(True,))
    return ForwardModel([b], SCHEMA, alpha_rule=rule)


def entity():
    f = np.zeros(D)
    f[0], f[Z] = 1.0, 0.80
    return f


def test_the_largest_group_for_each_next_state_gives_its_mean_alpha():
    fm = grasp_model(-20.0, 40.0, 25.0)
    chosen = dict((c, a[0]) for a, c in fm.choose_alphas(entity(), 0))
    step = 180.0 / 35  # the 36-point grid over [-90, 90]
    assert chosen[0] == pytest.approx(10.0, abs=step)     # the middle of the lifting window
    assert chosen[1] == pytest.approx(-55.0, abs=step)    # the larger of the two failing runs


def test_the_probability_rule_takes_the_most_probable_alpha_for_each_next_state():
    fm = grasp_model(-20.0, 40.0, 25.0, rule="probability")
    chosen = dict((c, a[0]) for a, c in fm.choose_alphas(entity(), 0))
    assert chosen[0] == pytest.approx(25.0, abs=180.0 / 35)  # the window's peak, not its middle


def test_a_group_may_wrap_round_a_full_circle():
    fm = grasp_model(340.0, 30.0, 5.0, rng=(0.0, 360.0))
    chosen = dict((c, a[0]) for a, c in fm.choose_alphas(entity(), 0))
    assert min(chosen[0], 360.0 - chosen[0]) == pytest.approx(5.0, abs=10.0)  # about 5 degrees, across 0
    assert 0.0 <= chosen[0] < 360.0
    assert _largest_run(np.array([True, False, False, True, True]), circle=True).tolist() == [3, 4, 0]
    assert _largest_run(np.array([True, False, False, True, True]), circle=False).tolist() == [3, 4]
    assert _mean_angle(np.array([350.0, 10.0])) == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize("rule", ["group", "probability"])
def test_a_plan_to_lift_uses_an_alpha_inside_the_window(rule):
    fm = grasp_model(-20.0, 40.0, 25.0, rule=rule)
    plan = best_first(fm, entity()[None, :], parse_goal(["0:cp_z>1.0"], SCHEMA), max_depth=1)
    assert plan.found and len(plan.steps) == 1
    alpha = plan.steps[0].alpha[0]
    assert -20.0 <= alpha <= 40.0
    assert plan.path_probability > 0.85
    grid = ForwardModel(fm.behaviors, SCHEMA)  # the 5-point grid misses the window's best
    coarse = best_first(grid, entity()[None, :], parse_goal(["0:cp_z>1.0"], SCHEMA), max_depth=1)
    assert coarse.path_probability < plan.path_probability


def test_an_unknown_rule_is_refused():
    with pytest.raises(ValueError, match="alpha rule"):
        grasp_model(-20.0, 40.0, 25.0, rule="dice")


def _planted_grasps(n=600, seed=0):
    """A grasp whose lifting depends on alpha alone (a window of approach angles), and an
    open-hand that never changes anything: chapter 9's empty-handed release."""
    from afford.features import Interactions

    rng = np.random.default_rng(seed)
    before = rng.normal(0.5, 0.1, (n, D))
    before[:, 0] = 1.0
    b = rng.integers(0, 2, n)
    alpha = rng.uniform(-90, 90, n)
    lifted = (b == 0) & (alpha > -20) & (alpha < 40)
    after = before.copy()
    after[lifted, Z] += 0.25
    spec = {"name": "alpha", "low": -90.0, "high": 90.0, "unit": "deg", "periodic": True}
    behaviors = [{"name": "power-grasp", "parameters": [spec], "target": "object"},
                 {"name": "open-hand", "parameters": [spec], "target": "object"}]
    data = Interactions.from_rows(SCHEMA, behaviors, before, after, b, alpha[:, None], np.arange(n), np.zeros(n))
    labels = np.where(lifted, 1, 0)
    return data, labels


def test_alpha_is_a_relevance_candidate_and_ranks_first_when_it_decides():
    from afford.learn.affordances import rank_features

    data, labels = _planted_grasps()
    rel = rank_features(data, labels, seed=0)
    score, rank = rel["power-grasp"].parameter_scores_["alpha"]
    assert rank == 1 and score > 0
    assert all(i < D for i in rel["power-grasp"].selected_)  # the entity's features; alpha goes in anyway
    assert rel["open-hand"].selected_.size == 0  # one effect only: nothing to tell apart


def test_a_behaviour_with_one_effect_trains_as_certain_beside_one_that_varies():
    from afford.learn.affordances import rank_features, train_predictors

    data, labels = _planted_grasps()
    rel = rank_features(data, labels, seed=0)
    models = train_predictors(data, labels, {k: v.selected_ for k, v in rel.items()}, seed=0)
    assert models["open-hand"].classes_.tolist() == [0]
    grasp = models["power-grasp"]
    inside = np.hstack([np.full((1, len(rel["power-grasp"].selected_)), 0.5), [[np.sin(np.radians(10)), np.cos(np.radians(10))]]])
    outside = inside.copy()
    outside[0, -2:] = [np.sin(np.radians(-70)), np.cos(np.radians(-70))]
    assert grasp.predict(inside)[0] == 1 and grasp.predict(outside)[0] == 0
