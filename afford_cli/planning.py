"""Planning in a scene, as ``plan``, ``emulate`` and the benchmarks run it."""

from __future__ import annotations

from afford.errors import AffordError
from afford.scenes_io import open_world

__all__ = ["parse_goals", "plan_once"]


def parse_goals(expressions: list[str], schema):
    from afford.plan.goals import GoalError, parse_goal

    try:
        return parse_goal(expressions, schema)
    except GoalError as exc:
        raise AffordError(str(exc)) from None


def plan_once(model, fm, scene, specs, seed: int, goal, method: str, limits: dict, execute: bool, max_replans: int,
              alternatives: int = 3) -> dict:
    """Plan in one scene (and execute with monitoring); the result as plain data.

    With ``alternatives`` > 1 the most probable plans are ranked by their success
    probability with monitoring, the first is the plan (and every replan is chosen the same
    way), and the others are reported under ``alternatives``.
    """
    from afford.plan.monitor import execute as run
    from afford.plan.monitor import rank_plans, ranked_planner

    world = open_world(scene, specs, seed)
    start = world.perceive()
    model.check_schema(scene.schema, "this scene's perception")
    goal.check_objects(start.shape[0])
    ranked = rank_plans(fm, start, goal, alternatives, max_replans=max_replans, method=method, **limits)
    first = ranked[0]
    out = {"seed": seed, "objects": start.shape[0], "plan": first.to_json(), "tree": first.tree[:12]}
    if alternatives > 1:
        out["alternatives"] = [p.to_json() for p in ranked[1:]]
    if execute and first.found:
        planner = ranked_planner(fm, goal, alternatives, max_replans=max_replans, method=method, **limits)
        result = run(world, fm, goal, method=method, max_replans=max_replans, first=first, planner=planner, **limits)
        out["execution"] = result.to_json()
        out["reached"] = result.reached
        out["replans"] = result.replans
        # did the first plan, as planned, work without replanning?
        out["first_plan_worked"] = result.reached and result.replans == 0 and result.windfalls == 0
    return out
