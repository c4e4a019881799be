"""Emulation success over varied start layouts (thesis 8.7's three tasks).

    python benchmarks/emulate.py [--model PATH | --interactions 5000] [--layouts 10] [--seed 42] [--max-depth 5] [--alternatives 3] [--tasks clear,lift,close]

For each task the shown scene is the example layout in examples/layouts, and the start
scenes are drawn at random (objects small enough to lift, within reach): clear the table
(one or two objects), bring an object to a shown lifted place, bring two objects together.
Prints one JSON object with the reached count per task and every run's outcome.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402

LAYOUTS = Path(__file__).resolve().parents[1] / "examples" / "layouts"


def small(shape: str, rng) -> tuple:
    d = float(rng.uniform(0.08, 0.14))
    return {"box": (d, d, float(rng.uniform(0.08, 0.14))), "cylinder": (d, float(rng.uniform(0.1, 0.16))),
            "sphere": (d,)}[shape]


def start_scene(task: str, i: int, rng):
    from afford.sim.objects import ObjectSpec

    shapes = ("box", "cylinder", "sphere")
    if task == "clear":
        objs: list = []
        while len(objs) < 1 + i % 2:
            x, y = float(rng.uniform(0.5, 0.8)), float(rng.uniform(-0.35, 0.35))
            if all(np.hypot(x - o.position[0], y - o.position[1]) > 0.25 for o in objs):
                s = shapes[int(rng.integers(3))]
                objs.append(ObjectSpec(s, small(s, rng), (round(x, 3), round(y, 3)), float(rng.uniform(0, 90))))
        return "empty-table.toml", objs
    if task == "lift":
        s = shapes[int(rng.integers(2))]
        x, y = float(rng.uniform(0.5, 0.75)), float(rng.uniform(-0.3, -0.1))
        return "lifted-shown.toml", [ObjectSpec(s, small(s, rng), (round(x, 3), round(y, 3)), float(rng.uniform(0, 90)))]
    y0 = float(rng.uniform(0.15, 0.3))
    x0, x1 = float(rng.uniform(0.5, 0.75)), float(rng.uniform(0.5, 0.75))
    return "close-shown.toml", [ObjectSpec("box", small("box", rng), (round(x0, 3), -round(y0, 3))),
                                ObjectSpec("cylinder", small("cylinder", rng), (round(x1, 3), round(y0, 3)))]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", help="a model artefact (default: explore and train one first)")
    ap.add_argument("--interactions", type=int, default=5000)
    ap.add_argument("--layouts", type=int, default=10)
    ap.add_argument("--seed", type=int, default=42)
    ap.add_argument("--max-depth", type=int, default=5)
    ap.add_argument("--alternatives", type=int, default=3, help="as afford emulate --alternatives")
    ap.add_argument("--tasks", default="clear,lift,close")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "emulate.json"))
    args = ap.parse_args()

    from afford.learning import forward_model, load_model
    from afford.scenes_io import open_world
    from afford.plan.emulate import goal_from_observation
    from afford.plan.monitor import execute, rank_plans, ranked_planner
    from afford.sim.layout import load_layout
    from afford.sim.registry import get_scene

    if args.model is None:
        from benchmarks.plan import build_model

        args.model = build_model(args.interactions, 1)
    model = load_model(args.model)
    scene = get_scene("table")()
    result = {"benchmark": "emulate", "tasks": {}}
    limits = {"max_depth": args.max_depth, "max_nodes": 20000}
    result["max_depth"] = args.max_depth
    result["alternatives"] = args.alternatives
    for task in args.tasks.split(","):
        rng = np.random.default_rng(args.seed)
        runs = []
        for i in range(args.layouts):
            shown_file, specs = start_scene(task, i, rng)
            shown = load_layout(LAYOUTS / shown_file)
            observed = open_world(scene, shown, i).perceive() if shown else np.empty((0, len(model.schema)))
            world = open_world(scene, specs, i + 1)
            fm = forward_model(model)
            goal = goal_from_observation(observed, world.perceive(), model.schema)
            start = world.perceive()
            plan = rank_plans(fm, start, goal, args.alternatives, **limits)[0]
            run = execute(world, fm, goal, first=plan, planner=ranked_planner(fm, goal, args.alternatives, **limits),
                          **limits) if plan.found else None
            runs.append({"found": plan.found, "reached": bool(run and run.reached), "replans": run.replans if run else 0,
                         "reason": run.reason if run else plan.reason, "length": len(plan.steps),
                         "success_probability": round(plan.success_probability, 4),
                         "open_loop_probability": round(plan.open_loop_probability or 0.0, 4)})
        found = [r for r in runs if r["found"]]
        result["tasks"][task] = {"reached": sum(r["reached"] for r in runs), "layouts": len(runs),
                                 "mean_success_probability": round(float(np.mean([r["success_probability"] for r in found])), 4) if found else None,
                                 "runs": runs}
    emit(result, args.out)


if __name__ == "__main__":
    main()
