"""``afford emulate``: be shown a scene, derive the goal, reach it from another scene."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import typer

from afford.commands.plan import render_plan
from afford.errors import AffordError
from afford.features.errors import DataError
from afford.learning import load_model
from afford.options import AlphaRule, AlphaRuleOpt, EffectModel, Effects, Alternatives, Json, MaxDepth, MaxNodes, MaxReplans, ModelScene
from afford.output import Output
from afford.plots import PlotFile, check_plot_file
from afford.scenes_io import model_scene, open_world, scene_layout


def emulate(
    model: Annotated[str, typer.Argument(help="A model artefact.", metavar="MODEL")],
    observe: Annotated[str, typer.Option("--observe", help="Layout of the scene the robot is shown (the goal).")],
    start: Annotated[str, typer.Option("--start", help="Layout of the scene the robot starts from.")],
    scene: ModelScene = None,
    execute: Annotated[bool, typer.Option("--execute/--no-execute", help="Run the plan in the simulator with monitoring.")] = True,
    max_depth: MaxDepth = 5,
    max_nodes: MaxNodes = 20000,
    max_replans: MaxReplans = 3,
    seed: Annotated[int, typer.Option("--seed", "-s", min=0, help="Seed of the simulated worlds (noise).")] = 0,
    alternatives: Alternatives = 3,
    plot: PlotFile = None,
    effects: Effects = EffectModel.members,
    alpha_rule: AlphaRuleOpt = AlphaRule.group,
    json: Json = False,
) -> None:
    """Emulate a shown goal scene (thesis 8.6-8.7): derive constraints, plan, execute, monitor."""
    from afford.plan.emulate import goal_from_observation

    check_plot_file(plot)
    loaded = load_model(model)
    loaded.effect_model = effects.value
    loaded.alpha_rule = alpha_rule.value
    loaded.check_effects("emulation")
    sc = model_scene(loaded, scene)
    _, shown = scene_layout(sc, None, observe, allow_empty=True)
    _, specs = scene_layout(sc, None, start)
    observed = open_world(sc, shown, seed).perceive() if shown else np.empty((0, len(loaded.schema)))
    world = open_world(sc, specs, seed + 1)
    state = world.perceive()
    try:
        goal = goal_from_observation(observed, state, loaded.schema)
    except DataError as exc:
        raise AffordError(str(exc)) from None
    limits = {"max_depth": max_depth, "max_nodes": max_nodes}
    out = Output(json)
    if execute:
        out.info(f"derived goal: {' and '.join(goal.to_json())}; searching for a plan")
    ranked = loaded.plans(state, goal, alternatives=alternatives, max_replans=max_replans, **limits)
    plan = ranked[0]
    result = {"goal": goal.to_json(), "plan": plan.to_json()["steps"], "found": plan.found,
              "success_probability": round(plan.success_probability, 4),
              "open_loop_probability": plan.to_json()["open_loop_probability"],
              "reached": False if execute else None, "replans": 0 if execute else None,
              "search": plan.to_json()}
    entry = {"plan": plan.to_json(), "tree": plan.tree[:8]}
    if alternatives > 1:
        result["alternatives"] = entry["alternatives"] = [p.to_json() for p in ranked[1:]]
    if execute and plan.found:
        ex = loaded.execute(world, goal, first=plan, alternatives=alternatives, max_replans=max_replans,
                            say=out.info, **limits)
        result.update({"reached": ex.reached, "replans": ex.replans, "execution": ex.to_json()})
        entry["execution"] = ex.to_json()
    elif not plan.found:
        result["reason"] = plan.reason
    if plot is not None:
        from afford.planning import draw_plan

        shown_rows = observed[loaded.schema.visible(observed)] if observed.size else None
        reached = f"; reached: {'yes' if result['reached'] else 'no'}" if execute and plan.found else ""
        result["plot"] = draw_plan(plot, loaded.schema, world, state, plan,
                                   world.perceive() if "execution" in result else None,
                                   f"emulate: {' and '.join(goal.to_json())}{reached}", shown=shown_rows)

    def render(console):
        console.print(f"shown: {len(shown)} object(s); derived goal: {' and '.join(goal.to_json())}")
        render_plan(console, entry, goal.to_json())

    out.result(result, render)
