"""Member effects: each object's own effect within its category (issue 17's forward model)."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features import FeatureSchema
from afford.learn.members import MemberEffects
from afford.plan.forward import BehaviorModel, ForwardModel
from afford.plan.goals import parse_goal
from afford.plan.monitor import blind_probability, reach_probability
from afford.plan.search import best_first


def _planted(n: int, rng, noise: float = 0.005):
    """Two features (width, colour) and one category whose push moves x by half the width
    (as a palm pushed to the centre does), a second category that never moves."""
    width = rng.uniform(0.08, 0.40, n)
    colour = rng.uniform(0, 1, n)  # irrelevant
    X = np.column_stack([width, colour])
    labels = (rng.random(n) < 0.5).astype(int)
    E = np.zeros((n, 2))
    E[labels == 0, 0] = width[labels == 0] / 2 + rng.normal(0, noise, (labels == 0).sum())
    return X, E, labels


def _members(X, E, labels, **kw):
    return MemberEffects(["position", "colour"], ["position", "colour"], [0.05, 0.1], **kw).fit(X, E, labels)


def test_member_effects_recover_a_planted_dependence_the_prototype_cannot():
    rng = np.random.default_rng(0)
    X, E, labels = _planted(600, rng)
    m = _members(X, E, labels)
    k = m.k_["position"]
    assert k != 0  # the prototype (every member) lost the leave-one-out choice
    assert m.loo_error_["position"][k] < 0.5 * m.loo_error_["position"][0]
    Xt, Et, lt = _planted(200, np.random.default_rng(1))
    moved = lt == 0
    pred = np.array([m.predict(x, 0)[0][0] for x in Xt[moved]])
    prototype = E[labels == 0, 0].mean()
    member_err = np.abs(pred - Et[moved, 0])
    prototype_err = np.abs(prototype - Et[moved, 0])
    assert np.median(member_err) < 0.01 < np.median(prototype_err)
    # the spread is the few members' own scatter, far below the category's
    assert m.predict(Xt[moved][0], 0)[1][0] < 0.3 * E[labels == 0, 0].std()


def test_member_effects_fall_back_on_the_prototype_when_features_tell_nothing():
    rng = np.random.default_rng(2)
    X = rng.uniform(0, 1, (500, 2))
    labels = np.zeros(500, dtype=int)
    E = np.column_stack([rng.normal(0.1, 0.03, 500), np.zeros(500)])  # pure noise around one mean
    m = _members(X, E, labels)
    # averaging more members only helps: every member (the prototype) or the largest count wins
    k, errors = m.k_["position"], m.loo_error_["position"]
    assert k in (0, 20)
    assert errors[k] <= min(errors[3], errors[5])


def test_nearest_members_are_those_a_full_stable_sort_finds_ties_included():
    """The partial sort that planning uses picks, per category, the same nearest members in the
    same order as sorting every member by distance (ties: the lower row), one query or many."""
    rng = np.random.default_rng(4)
    X, E, labels = _planted(400, rng)
    X[10:40] = X[5]  # thirty members at exactly one distance from any query: ties at the k-th
    labels = rng.integers(0, 3, labels.size)
    m = _members(X, E, labels, k_grid=(3, 5))
    queries = np.vstack([rng.uniform(0, 1, (20, 2)), X[5:6], X[[3, 70]]])
    for x in queries:
        # the distances exactly as the model computes them, then every member sorted
        d = np.empty(labels.size)
        d[m._perm] = m._sq - 2.0 * (((x - m.shift_) * m.weight_) @ m._ZT)
        for c in range(3):
            rows = np.flatnonzero(labels == c)
            for channel in m.channels:
                k = m.k_[channel]
                want = rows[np.argsort(d[rows], kind="stable")[:k]] if k else rows
                assert np.array_equal(m.neighbours(x, c, channel), want)
    batched, _ = m.means(queries)  # many queries take the partial sort; one query the full one
    assert np.array_equal(batched, np.stack([m.means(x)[0] for x in queries]))
    grouped = m._grouped(queries)
    for q, x in enumerate(queries):
        single = m._grouped(x)
        for start, count in m._blocks:
            k = min(count, m._kmax)
            assert np.array_equal(grouped[q, start: start + k], single[start: start + k])


def test_member_effects_round_trip_through_plain_arrays_and_refuse_parts_that_do_not_fit():
    rng = np.random.default_rng(3)
    X, E, labels = _planted(300, rng)
    m = _members(X, E, labels)
    arrays, meta = m.to_arrays()
    assert all(isinstance(a, np.ndarray) and a.dtype != object for a in arrays.values())
    back = MemberEffects.from_arrays(arrays, meta)
    x = np.array([0.3, 0.5])
    assert np.array_equal(back.predict(x, 0)[0], m.predict(x, 0)[0]) and back.k_ == m.k_
    assert np.allclose(back.means(x)[0][0], m.predict(x, 0)[0])
    with pytest.raises(ValueError):
        MemberEffects.from_arrays({**arrays, "E": arrays["E"][:5]}, meta)
    with pytest.raises(ValueError):
        MemberEffects.from_arrays({**arrays, "weight": arrays["weight"][:1]}, meta)
    with pytest.raises(ValueError):
        MemberEffects.from_arrays(arrays, {**meta, "k": "many"})
    with pytest.raises(ValueError):
        MemberEffects.from_arrays(arrays, {**meta, "k": {"position": 5}})  # a channel without its count
    # the pool of discarded members (label -1) travels with the rest and is checked the same way
    discarded = labels.copy()
    discarded[:40] = -1
    arrays, meta = _members(X, E, discarded).to_arrays()
    assert arrays["Zu"].shape == (40, 2) and arrays["Eu"].shape == (40, 2)
    assert np.array_equal(MemberEffects.from_arrays(arrays, meta).unknown_effects(x), _members(X, E, discarded).unknown_effects(x))
    bad = arrays["Eu"].copy()
    bad[3, 0] = np.nan
    with pytest.raises(ValueError):
        MemberEffects.from_arrays({**arrays, "Eu": bad}, meta)
    with pytest.raises(ValueError):
        MemberEffects.from_arrays({**arrays, "Eu": arrays["Eu"][:7]}, meta)
    with pytest.raises(ValueError):
        MemberEffects.from_arrays({k: a for k, a in arrays.items() if k != "Zu"}, meta)
    # a model from before the pool existed loads with an empty one
    old = MemberEffects.from_arrays({k: a for k, a in arrays.items() if k not in ("Zu", "Eu")}, meta)
    assert old.unknown_effects(x).shape == (0, 2)


class _Const:
    """A predictor that is sure of category 0 for every object."""

    classes_ = np.array([0, 1])

    def predict_proba(self, X):
        return np.tile([0.9, 0.1], (len(X), 1))


def _forward(effects: str, members: MemberEffects) -> tuple[ForwardModel, FeatureSchema]:
    schema = FeatureSchema(("x", "colour"), ("position", "colour"))
    prototypes = np.array([[members.E_[members.labels_ == 0, 0].mean(), 0.0], [0.0, 0.0]])
    b = BehaviorModel("push", _Const(), np.array([0, 1]), prototypes, members=members)
    return ForwardModel([b], schema, effects=effects), schema


def test_the_planner_moves_each_object_by_its_own_effect_and_rollouts_draw_from_its_members():
    rng = np.random.default_rng(4)
    X, E, labels = _planted(600, rng, noise=0.02)
    m = _members(X, E, labels)
    fm, schema = _forward("members", m)
    proto, _ = _forward("prototype", m)
    assert m.k_["position"] != 0
    narrow, wide = np.array([[0.10, 0.5]]), np.array([[0.38, 0.5]])
    # the member model tells a narrow object's push from a wide one's; the prototype does not
    assert fm.apply(narrow, 0, 0, 0)[0, 0] == pytest.approx(0.10 + 0.05, abs=0.02)
    assert fm.apply(wide, 0, 0, 0)[0, 0] == pytest.approx(0.38 + 0.19, abs=0.02)
    assert proto.apply(narrow, 0, 0, 0)[0, 0] - 0.10 == pytest.approx(proto.apply(wide, 0, 0, 0)[0, 0] - 0.38)
    # a goal tighter than the category's spread: x = 0.57 +- 0.03 for the wide object
    goal = parse_goal(["0:x=0.57~0.03"], schema)
    assert best_first(fm, wide, goal, max_depth=2).found
    plan = best_first(proto, wide, goal, max_depth=2)
    assert not plan.found or abs(proto.apply(wide, 0, 0, 0)[0, 0] - 0.57) <= 0.03
    # imagined worlds draw each push from the nearest members' own effects: a spread of ends,
    # so the chance of landing within 1 cm of the mean is below the category's 0.9, and above nothing
    aim = fm.apply(wide, 0, 0, 0)[0, 0]
    tight = parse_goal([f"0:x={aim:.4f}~0.01"], schema)
    tight_plan = best_first(fm, wide, tight, max_depth=1)
    assert tight_plan.found
    p = reach_probability(fm, wide, tight, tight_plan, max_replans=0, rollouts=200, seed=0)
    assert 0.05 < p < 0.85


class _Unsure:
    """P(known) of one half for every object."""

    classes_ = np.array([0, 1])

    def predict_proba(self, X):
        return np.tile([0.5, 0.5], (len(X), 1))


class _Sure:
    """A predictor certain of category 0."""

    classes_ = np.array([0, 1])

    def predict_proba(self, X):
        return np.tile([1.0, 0.0], (len(X), 1))


def test_an_unknown_kind_does_what_the_most_similar_discarded_members_did():
    """Half the pushes are of a kind the categories discarded, yet those pushes moved their
    objects as the kept ones did (their colour bins changed, say): imagined worlds that draw
    an unknown outcome from the discarded members expect the goal to be reached; without the
    pool an unknown outcome leaves the object put, and half the worlds miss it."""
    rng = np.random.default_rng(8)
    X, E, labels = _planted(800, rng)
    labels[:] = 0
    labels[rng.random(800) < 0.5] = -1
    E[labels == -1, 1] = 0.5  # a change the kept kind never shows, beside the same push
    E[:, 0] = X[:, 0] / 2 + rng.normal(0, 0.005, 800)
    schema = FeatureSchema(("x", "colour"), ("position", "colour"))
    wide = np.array([[0.38, 0.5]])

    def chance(m: MemberEffects) -> float:
        b = BehaviorModel("push", _Sure(), np.array([0, 1]), np.array([[E[labels == 0, 0].mean(), 0.0]]),
                          members=m, known=_Unsure())
        fm = ForwardModel([b], schema, effects="members")
        aim = fm.apply(wide, 0, 0, 0)[0, 0]
        goal = parse_goal([f"0:x={aim:.4f}~0.03"], schema)
        plan = best_first(fm, wide, goal, max_depth=1)
        assert plan.found and plan.success_probability == pytest.approx(0.5, abs=0.01)
        return reach_probability(fm, wide, goal, plan, max_replans=0, rollouts=300, seed=0)

    with_pool = _members(X, E, labels)
    assert with_pool.Eu_.shape[0] == (labels == -1).sum()
    arrays, meta = with_pool.to_arrays()
    without = MemberEffects.from_arrays({k: a for k, a in arrays.items() if k not in ("Zu", "Eu")}, meta)
    assert chance(with_pool) > 0.95
    assert 0.35 < chance(without) < 0.65


def _reference_means(m: MemberEffects, x: np.ndarray) -> np.ndarray:
    """Every category's member-effect mean for ``x`` the slow way: every member sorted by its
    distance (ties: the lower row), the nearest summed one after another."""
    d = np.empty(m.labels_.size)
    d[m._perm] = m._sq - 2.0 * (((x - m.shift_) * m.weight_) @ m._ZT)
    out = np.zeros((int(m.labels_.max()) + 1, m.E_.shape[1]))
    ch = np.asarray(m.effect_groups)
    for c in np.unique(m.labels_):
        rows = np.flatnonzero(m.labels_ == c)
        out[c] = m._E[rows].mean(axis=0)
        for channel in m.channels:
            k = m.k_[channel]
            if k == 0:
                continue
            near = rows[np.argsort(d[rows], kind="stable")[:k]]
            cols = ch == channel
            out[c, cols] = np.cumsum(m._E[near][:, cols], axis=0)[-1] / near.size
    return out


def test_member_means_are_the_nearest_members_sums_to_the_bit_one_behaviour_or_several():
    """The planner's fast paths (one partition over every category, several behaviours in one
    table) give the numbers a full sort and a plain running sum give, bit for bit: with ties
    at the k-th distance, categories smaller than k, one query or many."""
    from afford.learn.members import JointMembers

    rng = np.random.default_rng(5)
    models = []
    for seed, n, cats in ((0, 400, 3), (1, 250, 4)):
        X, E, _ = _planted(n, np.random.default_rng(seed))
        X[10:40] = X[5]  # thirty members at one distance from any query: ties at the k-th
        labels = rng.integers(0, cats, n)
        labels[rng.random(n) < 0.5] = 0
        labels[:12] = cats  # a category of 12 members: fewer than k = 20
        m = _members(X, E, labels, k_grid=(3, 5))
        m.k_ = {"position": 5, "colour": 20} if seed == 0 else {"position": 20, "colour": 3}
        m._index()
        models.append(m)
    queries = np.vstack([rng.uniform(0, 1, (25, 2)), models[0].Z_[:1] * 0 + [[0.3, 0.5]], _planted(5, rng)[0]])
    queries = np.vstack([queries, np.repeat(queries[:1], 2, axis=0)])
    queries[-1] = models[0].shift_ + models[0].Z_[5] / np.where(models[0].weight_ > 0, models[0].weight_, 1)
    joint = JointMembers(models)
    for x in queries:
        answers = joint.means([x, x])
        for m, (got, known) in zip(models, answers):
            want = _reference_means(m, x)
            assert np.array_equal(m.means(x)[0], want)
            assert np.array_equal(got, want) and np.array_equal(known, m._known)
    for m in models:
        assert np.array_equal(m.means(queries)[0], np.stack([_reference_means(m, x) for x in queries]))


def test_the_planner_answers_the_same_with_every_shortcut_as_without():
    """Member effects computed lazily and for every behaviour at once, and imagined replans
    that skip their open-loop figure: the same plans, next states and probabilities as
    asking one behaviour at a time."""
    rng = np.random.default_rng(6)
    X, E, labels = _planted(600, rng, noise=0.02)
    m = _members(X, E, labels)
    X2, E2, labels2 = _planted(500, np.random.default_rng(7), noise=0.03)
    m2 = _members(X2, -E2, labels2, k_grid=(3, 10))
    schema = FeatureSchema(("x", "colour"), ("position", "colour"))

    def forward(joint: bool) -> ForwardModel:
        behaviours = [BehaviorModel(name, _Const(), np.array([0, 1]),
                                    np.array([[mm.E_[mm.labels_ == 0, 0].mean(), 0.0], [0.0, 0.0]]), members=mm)
                      for name, mm in (("push", m), ("pull", m2))]
        fm = ForwardModel(behaviours, schema, effects="members")
        if not joint:
            fm._joint = None  # every behaviour asked on its own
        return fm

    fast, slow = forward(True), forward(False)
    assert fast._joint_members() is not None
    start = np.array([[0.30, 0.5]])
    for x in (0.10, 0.25, 0.38):
        f = np.array([x, 0.5])
        for b in (0, 1):
            assert np.array_equal(fast.apply(start * 0 + f, 0, b, 0), slow.apply(start * 0 + f, 0, b, 0))
    goal = parse_goal(["0:x=0.62~0.02"], schema)
    plans = [best_first(fm, start, goal, max_depth=3) for fm in (fast, slow)]
    assert plans[0].found and [(s.behavior, s.category, s.probability) for s in plans[0].steps] == \
        [(s.behavior, s.category, s.probability) for s in plans[1].steps]
    assert plans[0].success_probability == plans[1].success_probability
    quiet = best_first(forward(True), start, goal, max_depth=3, open_loop=False)
    assert [s.predicted.tobytes() for s in quiet.steps] == [s.predicted.tobytes() for s in plans[0].steps]
    assert quiet.path_probability == plans[0].path_probability and quiet.success_probability == 0.0
    p = [reach_probability(fm, start, goal, plan, rollouts=60, seed=3) for fm, plan in zip((fast, slow), plans)]
    assert p[0] == p[1] and 0.0 < p[0] < 1.0


class _LiftableNearZero:
    """Lift (category 0: the object rises) is likely only where the shape feature ``s`` lies
    within 1 of zero, as the crane's lift reads a flat top in the normal histograms."""

    classes_ = np.array([0, 1])

    def predict_proba(self, X):
        p = np.where(np.abs(np.asarray(X)[:, 1]) < 1.0, 0.95, 0.02)
        return np.column_stack([p, 1 - p])


def _move_then_lift(spread: float, rng) -> tuple[ForwardModel, FeatureSchema]:
    """A move that changes ``s`` by -2, give or take ``spread`` (a coin nothing in the entity
    foretells), and a lift that raises ``x`` by 1 where ``s`` is near zero."""
    schema = FeatureSchema(("x", "s"), ("position", "shape"))
    X = rng.uniform(0, 1, (400, 2))
    E = np.column_stack([rng.normal(0, 0.002, 400), -2 + spread * rng.choice([-1.0, 1.0], 400)])
    members = MemberEffects(["position", "shape"], ["position", "shape"], [0.05, 0.1]).fit(X, E, np.zeros(400, int))
    move = BehaviorModel("move", _Sure(), np.array([0, 1]), np.array([E.mean(axis=0), [0.0, 0.0]]), members=members)
    lift = BehaviorModel("lift", _LiftableNearZero(), np.array([0, 1]), np.array([[1.0, 0.0], [0.0, 0.0]]))
    return ForwardModel([move, lift], schema, effects="members"), schema


def test_a_plan_run_blind_is_judged_on_states_members_reached_not_on_their_mean():
    """Every move leaves ``s`` at -1.5 or +1.5, where lift fails; their mean, 0, is where it
    works. The open-loop walk judges lift on the mean state and expects the plan to work;
    blind rollouts draw whole member effects and expect it to fail, as it would. Where the
    members agree, the two figures agree."""
    start = np.array([[0.0, 2.0]])
    fm, schema = _move_then_lift(1.5, np.random.default_rng(11))
    goal = parse_goal(["0:x>0.5"], schema)
    plan = best_first(fm, start, goal, max_depth=2)
    assert [s.behavior for s in plan.steps] == ["move", "lift"]
    assert plan.success_probability > 0.85
    assert blind_probability(fm, start, goal, plan, rollouts=300, seed=0) < 0.1
    assert blind_probability(fm, start, goal, plan, rollouts=300, seed=0) == \
        blind_probability(fm, start, goal, plan, rollouts=300, seed=0)  # the seed fixes it
    sure, _ = _move_then_lift(0.0, np.random.default_rng(11))
    sure_plan = best_first(sure, start, goal, max_depth=2)
    p = blind_probability(sure, start, goal, sure_plan, rollouts=300, seed=0)
    assert p == pytest.approx(sure_plan.success_probability, abs=0.05)
