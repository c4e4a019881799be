"""Planning speed: three objects, four behaviours, plans up to depth 5.

    python benchmarks/plan.py [--model PATH] [--interactions 5000] [--scenes 20]

Without ``--model`` it explores and trains a model first (the time for that is reported
apart). Each scene draws three objects within reach and asks for all three to be gone
(plans of three or more steps) and for object 0 to end 20 cm further from the robot.
Search time is reported apart from the time to estimate the plan's success probability
with monitoring (``plan.monitor.assess``, which ``afford plan`` adds), and from the time to
rank the three most probable plans by that probability (``--alternatives 3``).

Beside it, on the same goals: the task as PDDL (``afford.plan.pddl``) solved by Fast
Downward (A* with LM-cut, extra ``afford[pddl]``): the time to write the PDDL, the planner's
time and its plan length. Both plans are then executed in the simulator: Fast Downward's
blind, afford's as ``afford plan --alternatives 1 --max-replans 0 --execute`` runs it (which
stops at the first surprise) and blind.
``crane``: the chapter-7 crane (``crane-lift``, 6 behaviours: 5 target-less moves and a
lift), breadth-first chaining to depth 4 in layouts of 5 objects, as ``afford plan --search
bfs --max-depth 4`` runs it: for the thesis's goal ``*:r_b>180`` (some object lifted) and for
one that never holds (``*:r_b>400``), which makes the search build the whole depth-4 tree
(its node budget, 20 000, permitting); seconds per plan and nodes per second, and the
seconds each plan found takes to get its blind probability (200 imagined blind runs).
``grasp_alpha_choice``: chapter 9's choice of alpha for one object and behaviour over a
36-point grid, by the largest-group rule and by the most probable alpha (milliseconds).
Prints one JSON object and writes it to ``--out``.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402


def build_model(interactions: int, seed: int) -> str:
    from afford.app import app
    from typer.testing import CliRunner

    d = Path(tempfile.mkdtemp(prefix="afford-bench-"))
    runner = CliRunner()
    for args in (["explore", "--interactions", str(interactions), "--seed", str(seed), "--workers", "2", "-o", str(d / "i.afford")],
                 ["cluster", str(d / "i.afford"), "-o", str(d / "e.afford")],
                 ["select-features", str(d / "e.afford"), "-o", str(d / "f.afford")],
                 ["train", str(d / "f.afford"), "-o", str(d / "m.afford")]):
        result = runner.invoke(app, args)
        if result.exit_code != 0:
            raise SystemExit(result.output)
    return str(d / "m.afford")


def crane(episodes: int, layouts: int, seed: int) -> dict:
    """Breadth-first chaining with the crane: 6 behaviours, 5 objects, depth 4."""
    import afford
    from afford.plan.monitor import blind_probability
    from afford.plan.search import breadth_first

    d = Path(tempfile.mkdtemp(prefix="afford-bench-crane-"))
    t = time.perf_counter()
    data = afford.explore("crane-lift", episodes=episodes, seed=seed, workers=2)
    afford.save(data, str(d / "i.afford"), seed=seed)
    afford.cluster(str(d / "i.afford"), str(d / "e.afford"), seed=seed)
    afford.train(str(d / "e.afford"), str(d / "m.afford"), seed=seed)
    model = afford.load_model(str(d / "m.afford"))
    built = time.perf_counter() - t
    fm = model.forward()
    out = {"episodes": episodes, "model_build_seconds": round(built, 1), "layouts": layouts, "max_depth": 4}
    for name, text in (("lift_some_object", "*:r_b>180"), ("never_holds", "*:r_b>400")):
        goal = afford.parse_goal(text, model.schema)
        secs, nodes, found, objects, blind = [], [], 0, [], []
        for i in range(layouts):
            sim = afford.world("crane-lift", seed=seed + 100 + i, objects=5)
            start = sim.perceive()
            objects.append(int(start.shape[0]))
            plan = breadth_first(fm, start, goal, max_depth=4)
            secs.append(plan.seconds)
            nodes.append(plan.expanded)
            found += plan.found
            if plan.found and plan.steps:  # the plan's blind probability: 200 imagined blind runs
                t = time.perf_counter()
                blind_probability(fm, start, goal, plan, rollouts=200, seed=i)
                blind.append(time.perf_counter() - t)
        secs, nodes = np.asarray(secs), np.asarray(nodes)
        out[name] = {"goal": text, "found": int(found), "objects_seen_mean": round(float(np.mean(objects)), 2),
                     "seconds_per_plan": {"mean": round(float(secs.mean()), 4), "max": round(float(secs.max()), 4)},
                     "expanded_per_plan": {"mean": round(float(nodes.mean()), 1), "max": int(nodes.max())},
                     "nodes_per_second": round(float(nodes.sum() / max(secs.sum(), 1e-9)), 1)}
        if blind:
            out[name]["blind_probability_seconds"] = {"mean": round(float(np.mean(blind)), 4),
                                                      "max": round(float(np.max(blind)), 4), "plans": len(blind)}
    return out


def alpha_choice(model_path: str | None, interactions: int, scenes: int, seed: int) -> dict:
    """Chapter 9: the cost of choosing alpha for one object and behaviour over the 36-point
    grid (thesis 9.5's largest group, and the most probable alpha), on random grasp scenes,
    each choice with a fresh cache (it pays for its 36 predictions)."""
    import afford
    from afford.learning import forward_model

    t = time.perf_counter()
    built = None
    if model_path is None:
        d = Path(tempfile.mkdtemp(prefix="afford-bench-grasp-"))
        data = afford.explore("grasp", interactions=interactions, seed=seed, workers=2)
        afford.save(data, str(d / "i.afford"), seed=seed)
        afford.cluster(str(d / "i.afford"), str(d / "e.afford"), seed=seed)
        afford.select_features(str(d / "e.afford"), str(d / "f.afford"), seed=seed)
        afford.train(str(d / "f.afford"), str(d / "m.afford"), seed=seed)
        model_path = str(d / "m.afford")
        built = round(time.perf_counter() - t, 1)
    model = afford.load_model(model_path)
    out = {"model_build_seconds": built, "interactions": interactions if built else None, "grid": 36}
    for rule in ("group", "probability"):
        ms = []
        for i in range(scenes):
            state = afford.world("grasp", seed=seed + 500 + i).perceive()
            for f in state:
                for b, behavior in enumerate(model.forward().behaviors):
                    if len(behavior.parameters) != 1:
                        continue
                    fm = forward_model(model, alpha_rule=rule)
                    t0 = time.perf_counter()
                    fm.choose_alphas(f, b)
                    ms.append(1000 * (time.perf_counter() - t0))
        ms = np.asarray(ms)
        out[rule] = {"choices": int(ms.size), "ms_mean": round(float(ms.mean()), 2) if ms.size else None,
                     "ms_max": round(float(ms.max()), 2) if ms.size else None}
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model")
    ap.add_argument("--interactions", type=int, default=5000)
    ap.add_argument("--scenes", type=int, default=20)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--crane-episodes", type=int, default=300, help="crane-lift episodes to learn from (0: skip the crane)")
    ap.add_argument("--crane-layouts", type=int, default=10)
    ap.add_argument("--effects", default="members", choices=["members", "prototype", "both"],
                    help="the forward model's effects (members: each object's own; prototype: the thesis's; both: "
                         "members, and beside it on every scene and goal, interleaved, prototype's assessment and "
                         "ranking times, reported under by_effects)")
    ap.add_argument("--grasp-model", help="a grasp model for the alpha-choice timing (default: explore and train one)")
    ap.add_argument("--grasp-interactions", type=int, default=3000, help="grasp interactions to learn from (0: skip)")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "plan.json"))
    args = ap.parse_args()
    t = time.perf_counter()
    model_path = args.model or build_model(args.interactions, args.seed)
    build_s = None if args.model else round(time.perf_counter() - t, 1)

    from afford.learning import forward_model, load_model
    from afford.scenes_io import open_world, scene_layout
    from afford.plan.goals import parse_goal
    from afford.plan.monitor import assess, rank_plans
    from afford.plan.search import best_first

    try:
        from afford.plan.pddl import build_task
        from afford.solvers import check_solver, run_blind, solve_pddl

        check_solver()
        pddl = True
    except Exception:  # the extra is not installed: no comparison
        pddl = False
    model = load_model(model_path)
    both = args.effects == "both"
    args.effects = "members" if both else args.effects
    model.effect_model = args.effects
    beside = []  # with --effects both: per scene and goal, the prototype's assess and rank3 times
    goals = {
        "all three gone": ["0:visibility=0", "1:visibility=0", "2:visibility=0"],
        "object 0 pushed 20 cm away": None,  # filled per scene
    }
    rows = []
    for s in range(args.scenes):
        scene, specs = scene_layout("table", args.seed + s, None, objects=3, reachable=True)
        state = open_world(scene, specs, args.seed + s).perceive()
        if state.shape[0] < 3:
            continue
        x = state[0, model.schema.index("x_min")]
        for name, exprs in goals.items():
            exprs = exprs or [f"0:x_min={x + 0.2:.3f}~0.06"]
            if both:  # the thesis's model on the same goal, just before the members model
                other = {}
                fm = forward_model(model, effects="prototype")
                goal = parse_goal(exprs, model.schema)
                plan = best_first(fm, state, goal, max_depth=5, max_nodes=20000)
                t0 = time.perf_counter()
                assess(fm, state, goal, plan, max_depth=5, max_nodes=20000)
                other["assess_seconds"] = time.perf_counter() - t0
                t0 = time.perf_counter()
                rank_plans(forward_model(model, effects="prototype"), state, goal, 3, max_depth=5, max_nodes=20000)
                other["rank3_seconds"] = time.perf_counter() - t0
                beside.append(other)
            fm = forward_model(model, effects=args.effects)  # a fresh cache: every plan pays for its own predictions
            goal = parse_goal(exprs, model.schema)
            plan = best_first(fm, state, goal, max_depth=5, max_nodes=20000)
            t0 = time.perf_counter()
            assess(fm, state, goal, plan, max_depth=5, max_nodes=20000)  # what `afford plan` adds
            assess_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            rank_plans(forward_model(model, effects=args.effects), state, goal, 3, max_depth=5, max_nodes=20000)  # --alternatives 3
            row = {"goal": name, "found": plan.found, "length": len(plan.steps), "seconds": plan.seconds,
                   "assess_seconds": assess_s, "rank3_seconds": time.perf_counter() - t0,
                   "expanded": plan.expanded, "generated": plan.generated, "predictions": fm.predictions}
            if pddl:
                t0 = time.perf_counter()
                task = build_task(forward_model(model, effects=args.effects), state, goal, max_depth=5)
                row["pddl_write_seconds"] = time.perf_counter() - t0
                fd = solve_pddl(task)
                row.update(fd_found=fd["solved"], fd_length=len(fd["steps"]), fd_seconds=fd["seconds"],
                           situations=len(task.situations))
                row["fd_reached"] = fd["solved"] and run_blind(open_world(scene, specs, args.seed + s), goal,
                                                               fd["steps"])["reached"]
                one = model.plans(state, goal, alternatives=1, max_replans=0)[0]
                row["afford_reached"] = one.found and model.execute(
                    open_world(scene, specs, args.seed + s), goal, first=one, alternatives=1, max_replans=0).reached
                row["afford_blind_reached"] = one.found and run_blind(
                    open_world(scene, specs, args.seed + s), goal, [(p.behavior, p.obj) for p in one.steps])["reached"]
            rows.append(row)
    secs = np.array([r["seconds"] for r in rows])
    nodes = np.array([r["expanded"] for r in rows])
    result = {
        "benchmark": "plan",
        "effects": args.effects,
        "model_build_seconds": build_s,
        "plans": len(rows),
        "found": int(sum(r["found"] for r in rows)),
        "seconds_per_plan": {"mean": round(float(secs.mean()), 4), "median": round(float(np.median(secs)), 4),
                             "max": round(float(secs.max()), 4)},
        "expanded_per_plan": {"mean": round(float(nodes.mean()), 1), "max": int(nodes.max())},
        "nodes_per_second": round(float(nodes.sum() / secs.sum()), 1),
        "success_probability_seconds": {"mean": round(float(np.mean([r["assess_seconds"] for r in rows])), 4),
                                        "max": round(float(np.max([r["assess_seconds"] for r in rows])), 4)},
        "alternatives_3_seconds": {"mean": round(float(np.mean([r["rank3_seconds"] for r in rows])), 4),
                                   "max": round(float(np.max([r["rank3_seconds"] for r in rows])), 4)},
        "by_goal": {g: {"found": sum(r["found"] for r in rows if r["goal"] == g),
                        "mean_length": round(float(np.mean([r["length"] for r in rows if r["goal"] == g and r["found"]] or [0])), 2),
                        "mean_seconds": round(float(np.mean([r["seconds"] for r in rows if r["goal"] == g])), 4)}
                    for g in goals},
    }
    if both:
        def mean(rs, key):
            return round(float(np.mean([r[key] for r in rs])), 4)

        result["by_effects"] = {
            "members": {"assess_seconds_mean": mean(rows, "assess_seconds"), "rank3_seconds_mean": mean(rows, "rank3_seconds")},
            "prototype": {"assess_seconds_mean": mean(beside, "assess_seconds"), "rank3_seconds_mean": mean(beside, "rank3_seconds")}}
        result["by_effects"]["ratio"] = {
            k: round(result["by_effects"]["members"][k] / max(result["by_effects"]["prototype"][k], 1e-9), 2)
            for k in ("assess_seconds_mean", "rank3_seconds_mean")}
    if pddl:
        def stat(key, g=None):
            vals = [r[key] for r in rows if g is None or r["goal"] == g]
            return {"mean": round(float(np.mean(vals)), 4), "max": round(float(np.max(vals)), 4)}

        result["fast_downward"] = {
            "write_pddl_seconds": stat("pddl_write_seconds"), "solve_seconds": stat("fd_seconds"),
            "situations": stat("situations"),
            "by_goal": {g: {"found": sum(r["fd_found"] for r in rows if r["goal"] == g),
                            "mean_length": round(float(np.mean([r["fd_length"] for r in rows
                                                                if r["goal"] == g and r["fd_found"]] or [0])), 2),
                            "reached_in_simulation": sum(bool(r["fd_reached"]) for r in rows if r["goal"] == g),
                            "afford_reached_in_simulation": sum(bool(r["afford_reached"]) for r in rows if r["goal"] == g),
                            "afford_blind_reached_in_simulation": sum(bool(r["afford_blind_reached"]) for r in rows
                                                                      if r["goal"] == g)}
                        for g in goals},
        }
    if args.crane_episodes:
        result["crane"] = crane(args.crane_episodes, args.crane_layouts, args.seed)
    if args.grasp_model or args.grasp_interactions:
        result["grasp_alpha_choice"] = alpha_choice(args.grasp_model, args.grasp_interactions, 10, args.seed)
    emit(result, args.out)


if __name__ == "__main__":
    main()
