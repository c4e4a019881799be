"""``afford pddl``: a model and a scene as PDDL and PPDDL, for off-the-shelf planners."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from afford.api import parse_goal
from afford.artifacts import write_artifact
from afford.errors import AffordError
from afford.features.errors import DataError
from afford.learning import load_model
from afford.options import EffectModel, Effects, Json, Layout, MaxDepth, Objects, ModelScene, SceneSeed, check_scene_source
from afford.output import Output
from afford.scenes_io import model_scene, open_world, scene_layout

FILES = ("domain.pddl", "problem.pddl", "domain.ppddl", "problem.ppddl")


def _check_out_dir(path: str) -> Path:
    """The directory for the PDDL files, checked before any work (not yet made)."""
    import os

    if path == "-":
        raise AffordError("pddl writes four files, not one stream; give a directory (-o DIR), not '-'")
    if not path:
        raise AffordError("give a directory for the PDDL files (-o DIR)")
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise AffordError(f"{path} is a file; give a directory for the PDDL files")
    where = out if out.exists() else (out.parent if str(out.parent) else Path("."))
    if not out.exists() and not where.is_dir():
        raise AffordError(f"cannot write {path}: {out.parent} does not exist")
    if not os.access(where, os.W_OK | os.X_OK):
        raise AffordError(f"cannot write {path}: permission denied")
    return out


def _out_dir(path: str) -> Path:
    out = _check_out_dir(path)
    if not out.exists():
        try:
            out.mkdir()
        except OSError as exc:
            raise AffordError(f"cannot write {path}: {exc.strerror.lower() if exc.strerror else exc}") from None
    return out


def pddl(
    model: Annotated[str, typer.Argument(help="A model artefact (effects discovered).", metavar="MODEL")],
    goal: Annotated[list[str], typer.Option("--goal", help="OBJ:FEATURE=VALUE~RANGE; repeat for several (all must hold).")],
    output: Annotated[str, typer.Option("--output", "-o", help="Directory for domain.pddl, problem.pddl, domain.ppddl, problem.ppddl.")],
    scene: ModelScene = None,
    seed: SceneSeed = None,
    objects: Objects = None,
    layout: Layout = None,
    max_depth: MaxDepth = 5,
    solve: Annotated[bool, typer.Option("--solve", help="Also solve the deterministic PDDL with Fast Downward (the optional pddl extra).")] = False,
    execute: Annotated[bool, typer.Option("--execute", help="Run Fast Downward's plan in the simulator, blind, and say whether the goal held (implies --solve).")] = False,
    effects: Effects = EffectModel.members,
    json: Json = False,
) -> None:
    """Write the model and the perceived scene as PDDL (determinised) and PPDDL (calibrated probabilities)."""
    from afford.plan.pddl import build_task

    check_scene_source(layout, seed, objects=objects)
    _check_out_dir(output)
    solve = solve or execute
    if solve:
        from afford.solvers import check_solver

        check_solver()
    loaded = load_model(model)
    loaded.effect_model = effects.value
    loaded.check_effects("PDDL")
    g = parse_goal(goal, loaded.schema)
    sc, specs = scene_layout(model_scene(loaded, scene), seed, layout, objects=objects)
    world = open_world(sc, specs, seed or 0)
    try:
        task = build_task(loaded.forward(), world.perceive(), g, max_depth=max_depth)
    except DataError as exc:
        raise AffordError(str(exc)) from None
    out = _out_dir(output)
    for name, text in zip(FILES, (task.domain, task.problem, task.ppddl_domain, task.ppddl_problem)):
        write_artifact(str(out / name), text.encode())
    result = {"output": str(out), "files": list(FILES), "goal": g.to_json(), **task.summary()}
    if solve:
        from afford.solvers import run_blind, solve_pddl

        result["fast_downward"] = solve_pddl(task)
        if execute and result["fast_downward"]["solved"]:
            result["execution"] = run_blind(world, g, result["fast_downward"]["steps"])

    def render(console):
        console.print(f"wrote {', '.join(FILES)} to {out}: {result['situations']} situations, "
                      f"{result['operators']} operators, {result['probabilistic_actions']} probabilistic actions"
                      + (" (PPDDL chaining stopped at its situation limit)" if task.truncated else ""))
        if solve:
            fd = result["fast_downward"]
            if fd["solved"]:
                console.print(f"Fast Downward ({fd['seconds']:.2f} s): "
                              + (", ".join(f"{b} on {o}" for b, o in fd["steps"]) or "nothing to do"))
            else:
                console.print(f"Fast Downward found no plan ({fd['status']})")
        if "execution" in result:
            console.print("[green]goal reached[/]" if result["execution"]["reached"] else "[red]goal not reached[/]")

    Output(json).result(result, render)
