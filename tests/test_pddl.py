"""PDDL for off-the-shelf planners: Fast Downward solves what afford's model says, and its
plans work in simulation about as often as afford's own."""

from __future__ import annotations

import re
import sys
from dataclasses import replace

import pytest
from typer.testing import CliRunner

import afford
from afford.app import app
from afford.plan.forward import ForwardModel
from afford.plan.pddl import PddlError, build_task
from afford.plan.search import best_first
from afford.solvers import run_blind, solve_pddl
from tests.test_plan import NUDGE, PUSH, SCHEMA, SWEEP, THROW, goal, scene

runner = CliRunner()


def test_fast_downward_finds_the_most_probable_plan_not_the_shortest():
    fm = ForwardModel([NUDGE, PUSH], SCHEMA)
    g = goal("0:x_min=0.4~0.01")
    task = build_task(fm, scene(0.0), g)
    fd = solve_pddl(task)
    # four sure nudges (cost 4) beat two pushes that each work 9 times in 10 (cost 24)
    assert fd["solved"] and fd["steps"] == [["nudge", 0]] * 4
    assert [s.behavior for s in best_first(fm, scene(0.0), g).steps] == ["nudge"] * 4
    assert fd["cost"] == 4


def test_unified_planning_reads_the_files(tmp_path):
    from unified_planning.io import PDDLReader

    fm = ForwardModel([PUSH, THROW, SWEEP], SCHEMA)
    task = build_task(fm, scene(0.0, 0.5), goal("0:x_min=0.2~0.01", "*:visibility=0"), max_depth=3)
    (tmp_path / "d.pddl").write_text(task.domain)
    (tmp_path / "p.pddl").write_text(task.problem)
    problem = PDDLReader().parse_problem(str(tmp_path / "d.pddl"), str(tmp_path / "p.pddl"))
    names = {a.name for a in problem.actions}
    assert {"push-c0", "sweep-c0", "finish"} <= names
    assert {o.name for o in problem.all_objects} >= {"o0", "o1", "s0"}


def test_goals_on_two_objects_and_on_some_object():
    fm = ForwardModel([PUSH, THROW, SWEEP], SCHEMA)
    fd = solve_pddl(build_task(fm, scene(0.0, 0.5), goal("0:x_min=0.2~0.01", "1:visibility=0")))
    assert sorted(map(tuple, fd["steps"])) == [("push", 0), ("sweep", 1)]
    fd = solve_pddl(build_task(fm, scene(0.0, 0.5), goal("*:visibility=0")))
    assert len(fd["steps"]) == 1 and fd["steps"][0][0] == "sweep"


def test_an_unreachable_goal_is_unsolvable():
    fm = ForwardModel([NUDGE], SCHEMA)
    fd = solve_pddl(build_task(fm, scene(0.0), goal("0:x_min=-0.3~0.01"), max_depth=3))
    assert not fd["solved"] and fd["steps"] == []


def test_ppddl_carries_the_calibrated_probabilities():
    fm = ForwardModel([PUSH, THROW], SCHEMA)
    task = build_task(fm, scene(0.0), goal("*:visibility=0"), max_depth=2)
    actions = {chunk.split("\n", 1)[0]: chunk for chunk in task.ppddl_domain.split("  (:action ")[1:]}

    def branches(name):
        return sorted(float(p) for p in re.findall(r"(\d\.\d{4}) \(and", actions[name]))

    # the 10 % no-change of push and the 50 % of throw move nothing: they are no branch, and
    # the rest of the probability mass leaves the state as it is
    assert branches("push-s0") == [0.9] and branches("throw-s0") == [0.5]
    assert "(probabilistic 0.9000 (and (not (at ?o s0)) (at ?o s1)" in actions["push-s0"]
    assert "(:requirements" in task.ppddl_domain and ":probabilistic-effects" in task.ppddl_domain


def test_what_pddl_cannot_express_is_refused():
    fm = ForwardModel([NUDGE], SCHEMA)
    with pytest.raises(PddlError, match="relates two objects' features"):
        build_task(fm, scene(0.0, 0.5), goal("0-1:x_min=0~0.01"))


def _replay(fm, state, steps):
    """The state the determinised model predicts after ``steps``."""
    for behavior, obj in steps:
        b = fm.index(behavior)
        state = fm.outcomes(state, obj, b, (), floor=0.0)[0].state
    return state


def test_fast_downward_plans_on_table_scenes_reach_the_goal_in_the_model_and_in_simulation(pipeline):
    model = afford.load_model(str(pipeline / "model.afford"))
    fm = model.forward()
    g = afford.parse_goal("*:visibility=0", model.schema)
    fd_reached = afford_reached = solved = 0
    for seed in range(6):
        state = afford.world("table", seed=seed, objects=1).perceive()
        task = build_task(fm, state, g)
        fd = solve_pddl(task)
        if fd["solved"]:
            solved += 1
            assert g.holds(_replay(fm, state, fd["steps"]))  # the PDDL says what the model says
            fd_reached += run_blind(afford.world("table", seed=seed, objects=1), g, fd["steps"])["reached"]
        plan = model.plan(state, g, alternatives=1, max_replans=0)
        if plan.found:
            run = model.execute(afford.world("table", seed=seed, objects=1), g, first=plan, alternatives=1,
                                max_replans=0)
            afford_reached += run.reached
    assert solved >= 4
    assert fd_reached >= afford_reached - 1 and fd_reached >= 3


def test_afford_pddl_writes_four_files_and_refuses_bad_input(pipeline, tmp_path, monkeypatch):
    out = tmp_path / "pddl"
    model = str(pipeline / "model.afford")
    result = runner.invoke(app, ["pddl", model, "--seed", "2", "--objects", "1", "--goal", "*:visibility=0",
                                 "-o", str(out), "--execute", "--json"])
    assert result.exit_code == 0, result.output
    assert sorted(p.name for p in out.iterdir()) == ["domain.pddl", "domain.ppddl", "problem.pddl", "problem.ppddl"]
    assert "(:action finish" in (out / "domain.pddl").read_text()
    # a relative goal, a file where the directory goes, a missing extra: one sentence each, exit 1
    bad = runner.invoke(app, ["pddl", model, "--seed", "2", "--objects", "2", "--goal", "0-1:x_min=0",
                              "-o", str(tmp_path / "rel")])
    assert bad.exit_code == 1 and "cannot express" in bad.output and not (tmp_path / "rel").exists()
    (tmp_path / "file").write_text("keep")
    bad = runner.invoke(app, ["pddl", model, "--seed", "2", "--goal", "*:visibility=0", "-o", str(tmp_path / "file")])
    assert bad.exit_code == 1 and "is a file" in bad.output and (tmp_path / "file").read_text() == "keep"
    monkeypatch.setitem(sys.modules, "unified_planning", None)
    monkeypatch.setitem(sys.modules, "unified_planning.io", None)
    bad = runner.invoke(app, ["pddl", model, "--seed", "2", "--goal", "*:visibility=0", "-o", str(out), "--solve"])
    assert bad.exit_code == 1 and "pip install 'afford[pddl]'" in bad.output
    assert len(bad.output.strip().splitlines()) == 1


def test_a_model_of_given_results_has_no_pddl():
    fm = ForwardModel([replace(NUDGE, prototypes=None)], SCHEMA)
    with pytest.raises(PddlError, match="labels were given"):
        build_task(fm, scene(0.0), goal("0:x_min=0.1~0.01"))
