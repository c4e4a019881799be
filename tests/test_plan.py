"""Planning on hand-made forward models: search, limits, goals, monitoring, emulation."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from afford.features import object_schema
from afford.plan.emulate import goal_from_observation
from afford.plan.forward import BehaviorModel, ForwardModel
from afford.plan.goals import GoalError, parse_goal
from afford.plan.monitor import assess, execute, rank_plans, reach_probability
from afford.plan.search import best_first, best_plans, breadth_first, inverse_query, success_probability

SCHEMA = object_schema()
D = len(SCHEMA)
X_MIN, X_MAX = SCHEMA.index("x_min"), SCHEMA.index("x_max")


class Fixed:
    """A 'predictor' with the same probabilities everywhere."""

    def __init__(self, probs):
        self.classes_ = np.arange(len(probs))
        self.p = np.asarray(probs, dtype=float)

    def predict_proba(self, X):
        return np.tile(self.p, (len(X), 1))


def effect(dx=0.0, vanish=False):
    e = np.zeros(D)
    e[X_MIN] = e[X_MAX] = dx
    if vanish:
        e[0] = -1.0
    return e


def behaviour(name, outcomes):
    """outcomes: list of (probability, effect vector)."""
    return BehaviorModel(name, Fixed([p for p, _ in outcomes]), np.array([0]), np.stack([e for _, e in outcomes]))


def obj(x=0.0):
    f = np.zeros(D)
    f[0] = 1.0
    f[X_MIN], f[X_MAX] = x, x + 0.1
    return f


def scene(*xs):
    return np.stack([obj(x) for x in xs])


NUDGE = behaviour("nudge", [(1.0, effect(0.1))])
PUSH = behaviour("push", [(0.9, effect(0.2)), (0.1, effect())])
THROW = behaviour("throw", [(0.5, effect(vanish=True)), (0.5, effect())])
SWEEP = behaviour("sweep", [(0.9, effect(vanish=True)), (0.1, effect(0.05))])


def goal(*exprs):
    return parse_goal(list(exprs), SCHEMA)


def test_breadth_first_finds_the_shortest_plan_best_first_the_most_probable():
    fm = ForwardModel([NUDGE, PUSH], SCHEMA)
    g = goal("0:x_min=0.4~0.01")
    short = breadth_first(fm, scene(0.0), g, max_depth=4)
    assert [s.behavior for s in short.steps] == ["push", "push"]
    probable = best_first(fm, scene(0.0), g, max_depth=4)
    assert [s.behavior for s in probable.steps] == ["nudge"] * 4
    assert probable.path_probability == pytest.approx(1.0)
    assert short.path_probability == pytest.approx(0.81)


def test_best_first_prefers_the_more_probable_of_two_plans():
    fm = ForwardModel([THROW, SWEEP], SCHEMA)
    plan = best_first(fm, scene(0.0), goal("*:visibility=0"))
    assert [s.behavior for s in plan.steps] == ["sweep"]
    assert plan.success_probability == pytest.approx(0.9)


def test_depth_and_node_limits_are_respected():
    fm = ForwardModel([NUDGE], SCHEMA)
    g = goal("0:x_min=0.3~0.01")
    assert best_first(fm, scene(0.0), g, max_depth=3).found
    shallow = best_first(fm, scene(0.0), g, max_depth=2)
    assert not shallow.found and "at most 2 steps" in shallow.reason
    starved = best_first(fm, scene(0.0), g, max_depth=5, max_nodes=2)
    assert not starved.found and "node budget" in starved.reason and starved.expanded == 2


def test_any_object_goal_acts_on_whichever_object_works_best():
    fm = ForwardModel([NUDGE], SCHEMA)
    plan = best_first(fm, scene(0.0, 0.25), goal("*:x_min=0.35~0.01"))
    assert [(s.behavior, s.obj) for s in plan.steps] == [("nudge", 1)]


def test_relative_goal_brings_two_objects_level():
    fm = ForwardModel([NUDGE], SCHEMA)
    plan = best_first(fm, scene(0.0, 0.2), goal("0-1:x_min=0~0.01"))
    assert [(s.behavior, s.obj) for s in plan.steps] == [("nudge", 0), ("nudge", 0)]


def test_vanished_objects_cannot_be_acted_on():
    fm = ForwardModel([NUDGE], SCHEMA)
    state = scene(0.0)
    state[0, 0] = 0.0
    assert not best_first(fm, state, goal("0:x_min=0.1~0.01")).found


def test_success_probability_counts_every_outcome_that_reaches_the_goal():
    fm = ForwardModel([THROW], SCHEMA)
    plan = best_first(fm, scene(0.0), goal("*:visibility=0"))
    assert plan.success_probability == pytest.approx(0.5)
    twice = plan.steps * 2  # a second throw after a first miss
    assert success_probability(fm, scene(0.0), goal("*:visibility=0"), twice) == pytest.approx(0.75)


def test_inverse_query_ranks_one_step_options():
    fm = ForwardModel([THROW, SWEEP, NUDGE], SCHEMA, min_probability=0.0)
    ranking = inverse_query(fm, scene(0.0), goal("*:visibility=0"))
    assert [(r["behavior"], r["probability"]) for r in ranking] == [("sweep", 0.9), ("throw", 0.5), ("nudge", 0.0)]


def test_goal_errors_are_one_sentence():
    with pytest.raises(GoalError, match="unknown feature 'colour'"):
        goal("0:colour=1")
    with pytest.raises(GoalError, match="cannot read goal"):
        goal("zero:x_min=1")
    with pytest.raises(GoalError, match="relates object 1 to itself"):
        goal("1-1:x_min=0")
    with pytest.raises(GoalError, match="robot sees 1 object"):
        goal("3:visibility=0").check_objects(1)
    g = goal("0:x_min=0.4", "*:visibility=0~0.2")
    assert g.to_json() == ["0:x_min=0.4~0.05", "*:visibility=0~0.2"]


class ScriptedWorld:
    """A world whose behaviours do what a script says, whatever the model predicts."""

    def __init__(self, state, script):
        self.state = state.copy()
        self.script = script  # behaviour name -> list of effects used in turn
        self.calls = []

    def perceive(self):
        return self.state.copy()

    def act(self, behavior, target, alpha=None):
        self.calls.append((behavior, target))
        effects = self.script[behavior]
        e = effects.pop(0) if len(effects) > 1 else effects[0]
        f = self.state[target] + e
        if f[0] < 0.5:
            self.state[target, 0] = 0.0
        else:
            self.state[target] = f
        return self.perceive()


def test_monitoring_replans_when_a_step_surprises():
    fm = ForwardModel([PUSH], SCHEMA)
    world = ScriptedWorld(scene(0.0), {"push": [effect(), effect(0.2), effect(0.2)]})  # the first push misses
    run = execute(world, fm, goal("0:x_min=0.4~0.01"), max_replans=3)
    assert run.reached and run.replans == 1
    assert [s["as_predicted"] for s in run.executed] == [False, True, True]


def test_monitoring_says_each_step_and_replan_as_it_happens():
    fm = ForwardModel([PUSH], SCHEMA)
    world = ScriptedWorld(scene(0.0), {"push": [effect(), effect(0.2), effect(0.2)]})  # the first push misses
    lines = []
    run = execute(world, fm, goal("0:x_min=0.4~0.01"), max_replans=3, say=lines.append)
    assert run.reached
    assert lines[0] == "searching for a plan" and lines[-1] == "goal reached"
    assert lines[1] == "executing step 1 of 2: push on object 0"
    assert lines[2].startswith("  step 1: surprise: object 0 ended")
    assert lines[3].startswith("replanning (replan 1 of at most 3): object 0 ended")
    assert lines[4] == "executing step 1 of 2 (plan 2): push on object 0" and lines[5] == "  step 1: as predicted"


def test_monitoring_stops_repeating_what_fails_and_tries_something_else():
    fm = ForwardModel([SWEEP, THROW], SCHEMA)
    world = ScriptedWorld(scene(0.0), {"sweep": [effect()], "throw": [effect(vanish=True)]})
    run = execute(world, fm, goal("*:visibility=0"), max_replans=3)
    assert run.reached
    assert world.calls == [("sweep", 0), ("throw", 0)]


def test_monitoring_gives_up_after_the_replan_budget():
    fm = ForwardModel([PUSH], SCHEMA)
    world = ScriptedWorld(scene(0.0), {"push": [effect(0.05)]})  # always a little, never as predicted
    run = execute(world, fm, goal("0:x_min=0.4~0.01"), max_replans=2)
    assert not run.reached and run.replans <= 2 and run.reason


def test_emulation_derives_goals_by_channel_priority():
    start = scene(0.0, 0.3)
    empty = goal_from_observation(np.empty((0, D)), start, SCHEMA)
    assert empty.to_json() == ["0:visibility=0~0.5", "1:visibility=0~0.5"]
    lifted = obj(0.5)
    lifted[SCHEMA.index("z_min")] = 1.0
    one = goal_from_observation(lifted[None, :], start, SCHEMA)
    assert {c.name for c in one.constraints} == {"x_min", "x_max", "y_min", "y_max", "z_min"}
    assert all(c.obj == "*" for c in one.constraints)
    two = goal_from_observation(scene(0.0, 0.1), start, SCHEMA)
    assert all(c.obj == (0, 1) for c in two.constraints)
    assert two.holds(scene(0.5, 0.6)) and not two.holds(start)


class Known:
    """P(the effect is of a kept kind) = 0.25 everywhere."""

    classes_ = np.array([0, 1])

    def predict_proba(self, X):
        return np.tile([0.75, 0.25], (len(X), 1))


def test_unknown_effects_lower_the_probabilities_plans_count_on():
    risky = BehaviorModel("risky", Fixed([1.0]), np.array([0]), np.stack([effect(vanish=True)]), known=Known())
    fm = ForwardModel([risky, SWEEP], SCHEMA)
    (out,) = fm.outcomes(scene(0.0), 0, 0)
    assert out.probability == pytest.approx(0.25)  # the rest is an outcome no plan counts on
    plan = best_first(fm, scene(0.0), goal("*:visibility=0"))
    assert [s.behavior for s in plan.steps] == ["sweep"]


PUSH_HALF = behaviour("push", [(0.6, effect(0.2)), (0.4, effect())])
SLIDE = behaviour("slide", [(0.5, effect(0.2)), (0.5, effect())])


def test_no_parameters_may_be_said_as_none():
    fm = ForwardModel([PUSH_HALF], SCHEMA)
    by_none = fm.outcomes(scene(0.0), 0, 0, None)
    assert [(o.category, o.probability) for o in by_none] == [(o.category, o.probability) for o in fm.outcomes(scene(0.0), 0, 0)]
    assert len(by_none) == 2 and by_none[0].probability == pytest.approx(0.6)


def test_reach_probability_imagines_monitored_execution():
    g = goal("0:x_min=0.4~0.01")
    fm = ForwardModel([PUSH_HALF], SCHEMA)
    plan = best_first(fm, scene(0.0), g)
    assert [s.behavior for s in plan.steps] == ["push", "push"]
    assert plan.success_probability == pytest.approx(0.36)  # both pushes must work, blind
    n = 1000
    se = 3 * np.sqrt(0.36 * 0.64 / n)
    # no replans: the open-loop figure, by sampling
    assert reach_probability(fm, scene(0.0), g, plan, max_replans=0, rollouts=n) == pytest.approx(0.36, abs=se)
    # A push that left the object where it was leaves it there again: with nothing else to
    # try, replanning cannot help (independent retries would claim 0.91).
    assert reach_probability(fm, scene(0.0), g, plan, max_replans=3, rollouts=n) == pytest.approx(0.36, abs=se)
    # With another behaviour to turn to, monitoring and replanning do help.
    both = ForwardModel([PUSH_HALF, SLIDE], SCHEMA)
    plan = best_first(both, scene(0.0), g)
    assert [s.behavior for s in plan.steps] == ["push", "push"]
    monitored = reach_probability(both, scene(0.0), g, plan, max_replans=3, rollouts=n, seed=1)
    assert monitored > 0.36 + 0.15
    assert reach_probability(both, scene(0.0), g, plan, max_replans=3, rollouts=n, seed=1) == monitored
    assessed = assess(both, scene(0.0), g, plan, max_replans=3, rollouts=n, seed=1)
    assert assessed.success_probability == monitored
    assert assessed.to_json()["open_loop_probability"] == pytest.approx(0.36)
    assert assessed.to_json()["replans_assumed"] == 3


def test_min_steps_bounds_the_steps_left_and_prunes_hopeless_branches():
    g = goal("0:visibility=0", "1:visibility=0", "2-3:x_min=0~0.01", "*:x_min=5~0.01")
    state = scene(0.0, 0.0, 0.0, 0.3)
    assert g.min_steps(state) == 3  # objects 0 and 1, and one of 2 and 3
    state[0, 0] = 0.0
    assert g.min_steps(state) == 2
    fm = ForwardModel([SWEEP], SCHEMA)
    three = goal("0:visibility=0", "1:visibility=0", "2:visibility=0")
    shallow = best_first(fm, scene(0.0, 0.5, 1.0), three, max_depth=2)
    assert not shallow.found and shallow.expanded == 1  # no child can finish in time
    assert best_first(fm, scene(0.0, 0.5, 1.0), three, max_depth=3).found


def test_while_the_hand_holds_an_object_only_that_object_is_acted_on():
    z = SCHEMA.index("z_min")
    up = np.zeros(D)
    up[z] = 0.3
    lift = behaviour("lift", [(0.9, up), (0.1, effect())])
    both_up = goal("0:z_min=0.3~0.01", "1:z_min=0.3~0.01")
    # one hand cannot hold two objects up: lifting the second would drop the first
    assert not best_first(ForwardModel([lift], SCHEMA, height=z), scene(0.0, 0.5), both_up).found
    assert best_first(ForwardModel([lift], replace(SCHEMA, roles=())), scene(0.0, 0.5), both_up).found  # cannot tell
    # lift one, then push it along: the object in the hand may still be acted on
    fm = ForwardModel([lift, NUDGE], SCHEMA, height=z)
    plan = best_first(fm, scene(0.0, 0.5), goal("0:z_min=0.3~0.01", "0:x_min=0.1~0.01"))
    assert plan.found and [s.obj for s in plan.steps] == [0, 0]
    # a replan that starts with object 1 in the hand lets go of it only where the goal
    # does not care about object 1
    assert not best_first(fm, scene(0.0, 0.5), goal("0:x_min=0.1~0.01", "1:x_min=0.5~0.01"), held=1).found
    assert best_first(fm, scene(0.0, 0.5), goal("0:x_min=0.1~0.01"), held=1).found


def test_reach_probability_stops_starting_rollouts_when_its_search_budget_is_spent():
    fm = ForwardModel([PUSH_HALF, SLIDE], SCHEMA)
    g = goal("0:x_min=0.4~0.01")
    plan = best_first(fm, scene(0.0), g)
    full = reach_probability(fm, scene(0.0), g, plan, rollouts=1000, seed=2)
    capped = reach_probability(fm, scene(0.0), g, plan, rollouts=1000, seed=2, budget=0)
    assert abs(capped - full) < 0.35
    assert assess(fm, scene(0.0), g, plan, rollouts=1000, seed=2).rollouts == 1000
    assert assess(fm, scene(0.0), g, plan, rollouts=1000, seed=2, budget=0).rollouts == 20


def test_a_surprise_that_helps_does_not_use_up_the_replans():
    # the first sweep sends object 0 off and knocks object 1 off too; later sweeps miss
    world = ScriptedWorld(scene(0.0, 0.5, 1.0), {"sweep": [effect()]})
    real_act = world.act

    def act(behavior, target, alpha=None):
        if not world.calls:
            world.calls.append((behavior, target))
            world.state[target, 0] = 0.0
            world.state[1 if target != 1 else 0, 0] = 0.0
            return world.perceive()
        return real_act(behavior, target, alpha)

    world.act = act
    fm = ForwardModel([SWEEP], SCHEMA)
    run = execute(world, fm, goal("0:visibility=0", "1:visibility=0", "2:visibility=0"), max_replans=1)
    assert run.windfalls == 1 and run.replans == 1 and len(world.calls) == 3
    assert "gave up after 1 replans" in run.reason  # a miss, by contrast, uses the budget up


class Raised:
    """P(category) depends on whether the object is up in the hand (its z_min feature)."""

    classes_ = np.array([0, 1])

    def __init__(self, held, on_table):
        self.held, self.on_table = np.asarray(held, float), np.asarray(on_table, float)

    def predict_proba(self, X):
        return np.where(X[:, :1] > 0.1, self.held, self.on_table)


def test_a_surprise_in_the_hand_is_distrusted_in_the_hand_only():
    z = SCHEMA.index("z_min")
    up, down = np.zeros(D), np.zeros(D)
    up[z], down[z] = 0.3, -0.3
    lift = behaviour("lift", [(0.9, up), (0.1, effect())])
    # dropping a held object off the table: likely by the model, which sees the held
    # object with the hand hiding its shape; from the table, less likely
    drops = [BehaviorModel(name, Raised([0.9, 0.1], [0.6, 0.4]), np.array([z]),
                           np.stack([effect(vanish=True), effect()])) for name in ("drop-left", "drop-right")]
    fm = ForwardModel([lift, *drops], SCHEMA, height=z)
    g = goal("0:visibility=0")
    assert [s.behavior for s in best_first(fm, scene(0.0), g).steps] == ["lift", "drop-left"]
    # this object lands back on the table when dropped; from the table, it goes
    world = ScriptedWorld(scene(0.0), {"lift": [up], "drop-left": [down, effect(vanish=True)],
                                       "drop-right": [down]})
    run = execute(world, fm, g, max_replans=3)
    assert run.reached and run.replans == 1
    # neither lift it and drop it the other way (that would begin with the same drop), nor
    # shun drop-left from the table for what it did in the hand
    assert world.calls == [("lift", 0), ("drop-left", 0), ("drop-left", 0)]


class NearOnly:
    """A 'predictor' with fixed probabilities where x_min < 1, and the last category beyond."""

    def __init__(self, probs):
        self.classes_ = np.arange(len(probs))
        self.p = np.asarray(probs, dtype=float)

    def predict_proba(self, X):
        out = np.tile(self.p, (len(X), 1))
        out[X[:, 0] >= 1.0] = np.eye(len(self.p))[-1]
        return out


def near_only(name, outcomes):
    return BehaviorModel(name, NearOnly([p for p, _ in outcomes]), np.array([X_MIN]), np.stack([e for _, e in outcomes]))


def test_best_plans_gives_different_sequences_most_probable_first():
    fm = ForwardModel([THROW, SWEEP], SCHEMA)
    plans = best_plans(fm, scene(0.0), goal("*:visibility=0"), 3, max_depth=2)
    sequences = [tuple(s.behavior for s in p.steps) for p in plans]
    assert sequences[:2] == [("sweep",), ("throw",)]
    assert len(set(sequences)) == len(sequences) == 3
    probabilities = [p.path_probability for p in plans]
    assert probabilities == sorted(probabilities, reverse=True)
    assert [s.behavior for s in best_first(fm, scene(0.0), goal("*:visibility=0")).steps] == ["sweep"]


def test_plans_are_ranked_by_their_chance_with_monitoring_not_by_their_path():
    # 'gamble' usually works but its failure pushes the object where nothing works any more;
    # 'sweep' works less often along its path, but a failed sweep can be swept again.
    gamble = near_only("gamble", [(0.95, effect(vanish=True)), (0.05, effect(5.0))])
    sweep = near_only("sweep", [(0.9, effect(vanish=True)), (0.1, effect(0.05))])
    fm = ForwardModel([gamble, sweep], SCHEMA)
    g = goal("*:visibility=0")
    assert [s.behavior for s in best_first(fm, scene(0.0), g).steps] == ["gamble"]
    ranked = rank_plans(fm, scene(0.0), g, 2, max_replans=3)
    assert [tuple(s.behavior for s in p.steps) for p in ranked] == [("sweep",), ("gamble",)]
    assert ranked[0].success_probability > ranked[1].success_probability
    assert ranked[1].success_probability == pytest.approx(0.95, abs=0.04)  # a failed gamble is not repaired
    assert rank_plans(fm, scene(0.0), g, 1)[0].steps[0].behavior == "gamble"  # one candidate: the most probable


class ReachWorld(ScriptedWorld):
    """A scripted world whose arm does not start on objects from ``x_min >= far``."""

    def __init__(self, state, script, far):
        super().__init__(state, script)
        self.far, self.last_executed = far, True

    def act(self, behavior, target, alpha=None):
        self.last_executed = self.state[target, X_MIN] < self.far
        if not self.last_executed:
            self.calls.append((behavior, target))
            return self.perceive()
        return super().act(behavior, target, alpha)


def test_an_object_the_arm_cannot_reach_is_left_alone():
    fm = ForwardModel([SWEEP, THROW], SCHEMA)
    world = ReachWorld(scene(0.5, 0.0), {"sweep": [effect(vanish=True)], "throw": [effect(vanish=True)]}, far=0.4)
    run = execute(world, fm, goal("*:visibility=0"), max_replans=3)
    assert run.reached and run.replans == 1
    assert world.calls == [("sweep", 0), ("sweep", 1)]  # nothing else tried on the far object
    assert "cannot reach object 0" in run.executed[0]["note"]


def test_when_the_goal_needs_an_object_out_of_reach_the_robot_says_so():
    fm = ForwardModel([SWEEP, THROW], SCHEMA)
    world = ReachWorld(scene(0.5), {"sweep": [effect(vanish=True)], "throw": [effect(vanish=True)]}, far=0.4)
    run = execute(world, fm, goal("0:visibility=0"), max_replans=3)
    assert not run.reached and run.replans == 1 and len(world.calls) == 1
    assert run.reason.startswith("no plan found") and "cannot reach object 0 where it lies" in run.reason


def test_a_behaviour_without_a_target_moves_every_seen_object_by_its_own_outcome():
    from afford.plan.forward import SCENE

    # a mobile robot drives: everything it sees shifts towards it, each object by its own effect
    drive = replace(behaviour("drive", [(0.8, effect(-0.3)), (0.2, effect())]), target=None)
    fm = ForwardModel([drive], SCHEMA, min_probability=0.0)
    start = scene(1.0, 2.0)
    outs = fm.outcomes(start, SCENE, 0)
    assert len(outs) == 4 and abs(sum(o.probability for o in outs) - 1.0) < 1e-9
    both = outs[0]
    assert both.category == (0, 0) and abs(both.probability - 0.64) < 1e-9
    assert np.allclose(both.state[:, X_MIN], [0.7, 1.7])
    # the planner chains such steps on the whole scene, and never on one object alone
    plan = best_first(fm, start, goal("0:x_min=0.4~0.02", "1:x_min=1.4~0.02"), max_depth=3)
    assert plan.found and [s.obj for s in plan.steps] == [SCENE, SCENE]
    assert abs(plan.path_probability - 0.64 ** 2) < 1e-9
    assert abs(success_probability(fm, start, goal("0:x_min=0.4~0.02", "1:x_min=1.4~0.02"), plan.steps)
               - 0.64 ** 2) < 1e-9


def test_planning_runs_blas_on_one_thread_and_gives_the_threads_back():
    from threadpoolctl import threadpool_info

    from afford.plan.forward import one_blas_thread

    def blas_threads():
        return {i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"}

    before = blas_threads()
    seen = one_blas_thread(blas_threads)()
    assert seen == {1}
    assert blas_threads() == before


class Aimed:
    """A push's outcome by where it is aimed (its last two columns: alpha's sine and cosine)
    and where the object stands (its first): near 20 degrees it moves the object 10 cm, a
    little off 5 cm, elsewhere not at all. Like a BLAS product, the last bits of a row's
    numbers depend on its place in its batch (the rows past the last multiple of four)."""

    def __init__(self):
        self.classes_ = np.arange(3)
        self.batches: list[int] = []

    def predict_proba(self, X):
        self.batches.append(len(X))
        a = np.degrees(np.arctan2(X[:, -2], X[:, -1]))
        off = np.abs(a - 20.0)
        far = 1.0 - np.clip(X[:, 0], 0.0, 0.5)  # the further out, the less it goes
        ten = np.where(off < 25.0, 0.75 * far, 0.05)
        five = np.where(off < 50.0, 0.2, 0.1)
        p = np.column_stack([ten, five, 1.0 - ten - five])
        tail = np.arange(len(X)) >= len(X) - len(X) % 4
        return p * (1.0 - 1e-13 * tail)[:, None]


def aimed(name, far, near):
    """A behaviour of one angle (an :class:`Aimed` predictor) whose outcomes move the object
    by ``far`` or ``near`` (dx, dy), or not at all."""
    def moved(dx, dy):
        e = effect(dx)
        e[SCHEMA.index("y_min")] = e[SCHEMA.index("y_max")] = dy
        return e

    return BehaviorModel(name, Aimed(), np.array([X_MIN]), np.stack([moved(*far), moved(*near), effect()]),
                         parameters=[(-90.0, 90.0)], periodic=(True,))


def aiming(cls=ForwardModel):
    """Two aimed pushes that move an object along different ways: a search meets many vectors."""
    return cls([aimed("aim", (0.1, 0.03), (0.05, -0.04)), aimed("swing", (0.08, -0.01), (0.02, 0.05))], SCHEMA,
               alpha_rule="group")


class Eager(ForwardModel):
    """The forward model as it was: every vector a prefetch meets gets its alpha choice at once."""

    def prefetch(self, vectors, only=None, alpha_only=None):
        super().prefetch(vectors, only, alpha_only)
        for b, key in list(self._owed):
            self._settle(b, key)


def test_alpha_choices_are_made_for_the_vectors_a_search_expands_with_the_same_numbers():
    g = goal("0:x_min=0.3~0.02")
    lazy = aiming()
    plan = best_first(lazy, scene(0.0), g, open_loop=False)
    assert plan.found and len(plan.steps) == 3

    def grids(fm):  # batches over the 36-point grid of alphas
        return sum(n == fm.alpha_grid for b in fm.behaviors for n in b.predictor.batches)

    # one batch per behaviour and vector the search expanded, not per vector it met
    assert grids(lazy) <= 2 * plan.expanded
    eager = aiming(Eager)
    assert best_first(eager, scene(0.0), g, open_loop=False).expanded == plan.expanded
    assert grids(eager) > 2 * grids(lazy)
    # ranked and assessed, the plans are the same to the bit: every batch is as it was
    lazy, eager = aiming(), aiming(Eager)
    a, b = (rank_plans(fm, scene(0.0), g, 3, rollouts=40) for fm in (lazy, eager))
    assert len(a) == len(b) == 3

    def bits(p):
        return ([(s.behavior, s.obj, s.alpha, s.category, s.probability, s.predicted.tobytes()) for s in p.steps],
                p.path_probability, p.success_probability, p.open_loop_probability, p.rollouts)

    assert [bits(p) for p in a] == [bits(p) for p in b]
    assert grids(lazy) < grids(eager)
    shared = [k for k in lazy._cache if k in eager._cache]
    assert shared and all(lazy._cache[k][1].tobytes() == eager._cache[k][1].tobytes() for k in shared)


def test_a_ranking_reports_its_search_and_assessment_as_they_go_and_times_both():
    from contextlib import contextmanager

    from afford.plan.search import watching

    events = []

    @contextmanager
    def progress(description, total):
        seen: list[int] = []
        events.append((description, total, seen))
        yield seen.append

    fm = aiming()
    g = goal("0:x_min=0.3~0.02")
    with watching(progress):
        ranked = rank_plans(fm, scene(0.0), g, 2, rollouts=30, max_nodes=500)
    # the imagined runs replan (a push falls short), yet their searches are the
    # assessment's work, not searches of their own
    assert [d.split()[0] for d, _, _ in events] == ["searching", "assessing"]
    (_, budget, nodes), (what, total, runs) = events
    assert budget == 500 and nodes == list(range(1, len(nodes) + 1)) and len(nodes) >= max(p.expanded for p in ranked)
    assert what.startswith("assessing 2 plans") and total == 60
    assert runs == sorted(runs) and runs[-1] == 60
    assert all(p.assess_seconds > 0 and p.to_json()["assess_seconds"] == round(p.assess_seconds, 4) for p in ranked)
    assert all(p.rollouts == 30 for p in ranked)
    # nobody listens outside the block
    events.clear()
    rank_plans(fm, scene(0.0), g, 2, rollouts=30)
    assert events == []


def test_one_plan_in_json_says_whether_it_was_found_and_nothing_reached_when_nothing_ran(pipeline):
    import json

    from tests.clitools import ok

    model = str(pipeline / "model.afford")
    args = ["plan", model, "--seed", "3", "--reachable", "--max-depth", "1", "--alternatives", "1", "--json"]
    out = json.loads(ok(args + ["--goal", "*:visibility=0"]).stdout)
    assert out["found"] is True and out["plan"]["found"] is True  # the plan's verdict, not a count of scenes
    assert out["success_probability"] == out["plan"]["success_probability"]
    assert out["reached"] is None and out["replans"] is None  # nothing ran
    assert [v["reached"] for v in out["by_length"].values()] == [None]
    assert out["planning_seconds"] == pytest.approx(out["search_seconds"] + out["assess_seconds"], abs=2e-4)
    assert out["assess_seconds"] == out["plan"]["assess_seconds"] > 0
    none = json.loads(ok(args + ["--goal", "0:x_min=5~0.01"]).stdout)
    assert none["found"] is False and none["reason"] == none["plan"]["reason"] and none["by_length"] == {}
    episodes = json.loads(ok(args + ["--goal", "*:visibility=0", "--episodes", "2"]).stdout)
    assert episodes["found"] == sum(v["found"] for v in episodes["by_length"].values())  # a count, over scenes
    assert all(v["reached"] is None for v in episodes["by_length"].values()) and "reached" not in episodes


def test_slow_searches_and_assessments_show_a_bar_on_stderr_and_quick_ones_do_not(capsys):
    from afford.output import Output
    from afford.planning import progress_bars
    from afford.plan.search import watching

    g = goal("0:x_min=0.3~0.02")
    with watching(progress_bars(Output(), after=0.0)):  # everything is slow
        rank_plans(aiming(), scene(0.0), g, 2, rollouts=30, max_nodes=500)
    captured = capsys.readouterr()
    assert captured.out == ""
    lines = [ln for ln in captured.err.splitlines() if ln.strip()]
    assert len(lines) == 2 and lines[0].startswith("searching") and lines[1].startswith("assessing 2 plans")
    assert "60/60" in lines[1]
    with watching(progress_bars(Output())):  # nothing here takes seconds
        rank_plans(aiming(), scene(0.0), g, 2, rollouts=30, max_nodes=500)
    assert capsys.readouterr().err == ""


def test_a_scenes_joint_outcomes_are_the_full_products_above_the_floor_in_its_order_and_bits():
    """A move changes every object: its outcomes are the product of each object's categories.
    The search enumerates only the branches that can still reach the floor; what it keeps
    must be exactly what filtering the whole product keeps."""
    import itertools
    import math

    from afford.plan.forward import _joint

    rng = np.random.default_rng(7)
    for trial in range(400):
        n = int(rng.integers(0, 6))
        choices = []
        for _ in range(n):
            k = int(rng.integers(1, 5))
            p = rng.dirichlet(np.ones(k) * rng.uniform(0.2, 2.0))
            kept = [(int(c), float(q)) for c, q in enumerate(p) if q >= 0.01] or [(None, 1.0)]
            choices.append(kept)
        floor = float(rng.choice([0.0, 0.01, 0.05, 0.2]))
        full = [(tuple(c for c, _ in combo), math.prod(q for _, q in combo)) for combo in itertools.product(*choices)]
        want = [(c, p) for c, p in full if p >= floor]
        got = _joint(choices, floor)
        assert got == want and all(type(p) is float for _, p in got)
    # five objects of four likely categories: most of the thousand combinations are never built
    assert len(_joint([[(0, 0.4), (1, 0.3), (2, 0.2), (3, 0.1)]] * 5, 0.01)) < 100
