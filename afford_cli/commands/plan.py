"""``afford plan``: find the behaviour sequence most likely to reach a goal; run it if asked."""

from __future__ import annotations

from enum import Enum
from typing import Annotated

import typer
from rich import box
from rich.table import Table

from afford.errors import AffordError
from afford.features.errors import DataError
from afford.learning import load_model
from afford.options import (
    AlphaRule, AlphaRuleOpt, BlindRollouts, EffectModel, Effects,
    Alternatives, Json, Layout, MaxDepth, MaxNodes, MaxReplans, ModelScene, Objects, SceneSeed, check_scene_source,
)
from afford.output import Output
from afford.plots import PlotFile, check_plot_file
from afford.api import parse_goal
from afford.planning import plan_once, progress_bars
from afford.scenes_io import model_scene, scene_layout
from afford.plan.report import summarise


class SearchMethod(str, Enum):
    best_first = "best-first"
    bfs = "bfs"


def _on(obj: int) -> str:
    """What a step acted on, as a report says it (a behaviour without a target: the scene)."""
    from afford.plan.forward import SCENE

    return "the scene" if obj == SCENE else f"object {obj}"


def render_plan(console, entry: dict, goal_text: list[str]) -> None:
    p = entry["plan"]
    console.print(f"goal: {' and '.join(goal_text)}")
    if not p["found"]:
        console.print(f"[red]no plan[/]: {p['reason']} ({p['expanded']} nodes expanded, "
                      f"{entry.get('planning_seconds', p['seconds']):.2f} s)")
        return
    if "planning_seconds" in entry:  # the search and the candidates' assessment
        n = 1 + len(entry.get("alternatives", []))
        effort = (f"{p['expanded']} nodes expanded; {entry['planning_seconds']:.2f} s: searching "
                  f"{entry['search_seconds']:.2f} s, assessing {n} candidate{'s' * (n != 1)} {entry['assess_seconds']:.2f} s")
    else:
        effort = f"{p['expanded']} nodes expanded, {p['seconds'] * 1000:.0f} ms searching"
    console.print(f"plan: {p['length']} step{'s' if p['length'] != 1 else ''} ({effort}); success probability "
                  f"{p['success_probability']:.2f} with monitoring and up to {p['replans_assumed']} replans, "
                  f"{p['open_loop_probability']:.2f} run blind"
                  + (f" ({p['blind_probability']:.2f} in {p['blind_rollouts']} imagined blind runs)"
                     if "blind_probability" in p else ""))
    table = Table(box=box.SIMPLE_HEAD)
    for col in ("step", "behaviour", "object", "alpha", "expected category", "p"):
        table.add_column(col)
    for i, s in enumerate(p["steps"], 1):
        table.add_row(str(i), s["behavior"], str(s["object"]), ", ".join(f"{a:.2f}" for a in s["alpha"]) or "-",
                      str(s["category"]), f"{s['probability']:.2f}")
    console.print(table)
    if entry.get("alternatives"):
        console.print("other plans, by success probability with monitoring (run blind / along the path):")
        for rank, a in enumerate(entry["alternatives"], 2):
            steps = ", ".join(f"{s['behavior']} {s['object']}" for s in a["steps"])
            console.print(f"  {rank}. {steps}: {a['success_probability']:.2f} ({a['open_loop_probability']:.2f} / "
                          f"{a['path_probability']:.2f})")
    if entry.get("tree"):
        console.print("search tree, first level (behaviour on object -> category, p, distance to goal):")
        for n in entry["tree"]:
            console.print(f"  {n['behavior']} on {_on(n['object'])} -> {n['category']} p={n['probability']:.2f} d={n['distance']:.2f}")
    if "execution" in entry:
        ex = entry["execution"]
        for s in ex["executed"]:
            mark = "[green]as predicted[/]" if s["as_predicted"] else f"[yellow]{s['note']}[/]"
            console.print(f"  ran {s['behavior']} on {_on(s['object'])}: {mark}")
        verdict = "[green]goal reached[/]" if ex["reached"] else f"[red]not reached[/]: {ex['reason']}"
        extra = f", and {ex['windfalls']} after surprises that helped" if ex.get("windfalls") else ""
        console.print(f"{verdict} (replans: {ex['replans']}{extra})")


def plan(
    model: Annotated[str, typer.Argument(help="A model artefact.", metavar="MODEL")],
    goal: Annotated[list[str], typer.Option("--goal", help="OBJ:FEATURE=VALUE~RANGE; repeat for several (all must hold).")],
    scene: ModelScene = None,
    seed: SceneSeed = None,
    objects: Objects = None,
    layout: Layout = None,
    max_depth: MaxDepth = 5,
    max_nodes: MaxNodes = 20000,
    method: Annotated[SearchMethod, typer.Option("--search", help="Most probable plan (best-first) or the thesis's breadth-first chaining.")] = SearchMethod.best_first,
    execute: Annotated[bool, typer.Option("--execute", help="Run the plan in the simulator, monitor it and replan on surprises.")] = False,
    max_replans: MaxReplans = 3,
    blind_rollouts: BlindRollouts = 0,
    episodes: Annotated[int, typer.Option("--episodes", min=1, help="Plan in this many random scenes (seeds S, S+1, ...) and report rates.")] = 1,
    reachable: Annotated[bool, typer.Option("--reachable", help="Draw only objects within the arm's reach.")] = False,
    button: Annotated[bool, typer.Option("--button", help="Add the fixed flat button of thesis 7.6.5 to a drawn scene (crane-lift).")] = False,
    alternatives: Alternatives = 3,
    plot: PlotFile = None,
    effects: Effects = EffectModel.members,
    alpha_rule: AlphaRuleOpt = AlphaRule.group,
    json: Json = False,
) -> None:
    """Plan a behaviour sequence in the robot's own perceptual space to reach a goal."""
    check_scene_source(layout, seed, objects=objects, reachable=reachable or None, button=button or None,
                       episodes=episodes if episodes > 1 else None)
    if plot is not None and episodes > 1:
        raise typer.BadParameter("--plot draws one scene; it does not go with --episodes")
    check_plot_file(plot)
    loaded = load_model(model)
    loaded.effect_model = effects.value
    loaded.alpha_rule = alpha_rule.value
    loaded.check_effects("planning")
    g = parse_goal(goal, loaded.schema)
    limits = {"max_depth": max_depth, "max_nodes": max_nodes}
    out = Output(json)
    base = seed or 0
    entries = []
    # a scene the model cannot perceive is refused once, not skipped episode by episode
    scene = model_scene(loaded, scene)
    if episodes == 1:
        sc, specs = scene_layout(scene, seed, layout, objects=objects, reachable=reachable, button=button)
        entries.append(plan_once(loaded, sc, specs, base, g, method.value, limits, execute, max_replans, alternatives,
                                 say=out.info if execute else None, plot=plot, progress=progress_bars(out),
                                 blind_rollouts=blind_rollouts))
    else:
        with out.progress("planning episodes", episodes) as update:
            for e in range(episodes):
                sc, specs = scene_layout(scene, base + e, None, objects=objects, reachable=reachable, button=button)
                try:
                    entries.append(plan_once(loaded, sc, specs, base + e, g, method.value, limits, execute, max_replans,
                                             alternatives, blind_rollouts=blind_rollouts))
                except (AffordError, DataError) as exc:  # e.g. an object hidden behind another
                    entries.append({"seed": base + e, "skipped": str(exc),
                                    "plan": {"found": False, "seconds": 0.0, "expanded": 0, "length": 0}})
                update(e + 1)
    result = summarise(entries, execute)
    result["goal"] = g.to_json()
    if episodes == 1:
        result.update(single_plan(entries[0], execute))

    def render(console):
        if episodes == 1:
            render_plan(console, entries[0], g.to_json())
        else:
            render_summary(console, result)

    out.result(result, render)


def single_plan(entry: dict, execute: bool) -> dict:
    """The top-level keys of one plan's ``--json``, as ``emulate`` gives them: ``found`` (a
    bool), ``reason`` when no plan was found, the success probabilities, and ``reached`` and
    ``replans`` (null when nothing ran: no ``--execute``; false and 0 when no plan was found
    to run). The episodes summary's keys stay beside them, counted over this one scene."""
    p = entry["plan"]
    out = {"found": bool(p["found"]), "success_probability": p["success_probability"],
           "open_loop_probability": p["open_loop_probability"],
           **({"blind_probability": p["blind_probability"]} if "blind_probability" in p else {}),
           "reached": False if execute else None, "replans": 0 if execute else None}
    if execute:
        out["first_plan_worked"] = False
    if not p["found"]:
        out["reason"] = p["reason"]
    out.update(entry)
    return out


def render_summary(console, result: dict) -> None:
    skipped = f" ({result['skipped']} skipped: the robot did not see every object the goal names)" if result["skipped"] else ""
    table = Table(title=f"{result['episodes']} scenes{skipped}: plans found {result['found']}"
                        + (f", goal reached {result['reached']}" if "reached" in result else ""), box=box.SIMPLE_HEAD)
    for col in ("plan length", "found", "reached", "rate"):
        table.add_column(col, justify="right")
    for k, v in result["by_length"].items():
        rate = f"{100 * v['reached'] / v['found']:.0f}%" if "reached" in result and v["found"] else "-"
        table.add_row(k, str(v["found"]), str(v["reached"]) if "reached" in result else "-", rate)
    console.print(table)
    if result["mean_success_probability"] is not None:
        reached = (f" (goal reached in {result['reached']} of {result['found']})" if "reached" in result else "")
        console.print(f"mean predicted success probability with monitoring {result['mean_success_probability']:.2f}{reached}; "
                      f"run blind {result['mean_open_loop_probability']:.2f}"
                      + (f" ({result['mean_blind_probability']:.2f} in imagined blind runs)"
                         if result.get("mean_blind_probability") is not None else "")
                      + (f" (first plans that worked without replanning: {result['first_plan_worked']} of {result['found']})"
                         if "first_plan_worked" in result else ""))
    console.print(f"mean search: {result['mean_expanded']:.0f} nodes, {1000 * result['mean_seconds']:.0f} ms; "
                  f"with the candidates' assessment {result['mean_planning_seconds']:.2f} s")
