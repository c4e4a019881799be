"""Putting objects where they are asked: positioning goals executed with monitoring, for the
member-effect forward model and the thesis's prototype one, on the same scenes.

    python benchmarks/position.py [--model PATH] [--interactions 5000] [--scenes 100] [--clear 30]

Each scene draws one object within reach (scene seeds 20 000 + ``--seed`` * 1000 + i, never
used by the tests or the other benchmarks). Where the object can go is found in simulation,
not assumed: every sequence of one or two pushes (push-left, push-right, push-forward) is run
from the start in a fresh world, and the object's lateral position ``y_min`` after each is
kept. A target V is then drawn uniformly within 30 cm of the start, and accepted when one of
those sequences ends within the goal's 5 cm of it and the start does not (at most 50 draws;
a scene with none is skipped). The goal ``0:y_min=V~0.05`` is planned for (``afford plan``'s
defaults: three alternatives, each ranked by its probability of success with up to three
replans) and executed with monitoring (``afford plan --execute``), once per effect model.

``--targets free`` draws V without looking at any outcome instead: 10-25 cm to the left or
right of the start (a side chosen at random among those where the object's whole footprint,
as perceived, stays on the table), so the scenes kept are not the ones where the world was
kind, and the predicted success can be compared with the reached rate without selection
bias. ``--targets model`` lets the robot choose V from its own forward model, again before
any outcome: where the most likely outcome of push-left or push-right (a side at random of
those that move the object 8 cm or more and keep it on the table) is predicted to leave
``y_min``. ``--effects`` runs one forward model only.

``--clear`` scenes of three objects within reach ask for all three gone (``*:visibility=0``
for each), executed the same way: clearing must stay as good as it was.

Beside the plans: the held-out effect error of both forward models (``afford evaluate``'s
``effect_error``) on ``--test`` interactions of another seed. Prints one JSON object and
writes it to ``--out``.
"""

from __future__ import annotations

import argparse
import itertools
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402

EFFECTS = ("members", "prototype")
PUSHES = ("push-left", "push-right", "push-forward")
SEQUENCES = [list(s) for n in (1, 2) for s in itertools.product(PUSHES, repeat=n)]


def reachable(model_path: str, seed: int) -> tuple[float, list[float]] | None:
    """The start's y_min and where each push sequence leaves it (None: no object seen)."""
    from afford import api

    m = api.load_model(model_path)
    iy = m.schema.index("y_min")
    start = api.world("table", seed=seed, objects=1, reachable=True).perceive()
    if start.shape[0] < 1 or not m.schema.visible(start[0]):
        return None
    ends = []
    for seq in SEQUENCES:
        w = api.world("table", seed=seed, objects=1, reachable=True)
        w.perceive()
        for b in seq:
            after = w.act(b, 0)
        if after.shape[0] and m.schema.visible(after[0]):
            ends.append(float(after[0, iy]))
    return float(start[0, iy]), ends


def run_goal(model_path: str, seed: int, goal: list[str], objects: int, effects=EFFECTS) -> dict | None:
    """Plan and execute ``goal`` in the scene of ``seed`` with each effect model (None: fewer
    than ``objects`` objects seen at the start)."""
    from afford import api

    m = api.load_model(model_path)
    if api.world("table", seed=seed, objects=objects, reachable=True).perceive().shape[0] < objects:
        return None
    out = {}
    for effect_model in effects:
        m.effect_model = effect_model
        w = api.world("table", seed=seed, objects=objects, reachable=True)
        t = time.perf_counter()
        plan = m.plan(w.perceive(), goal)
        plan_s = time.perf_counter() - t
        run = m.execute(w, goal, first=plan) if plan.found else None
        out[effect_model] = {"found": plan.found, "length": len(plan.steps), "p": plan.success_probability,
                        "p_open_loop": plan.open_loop_probability, "reached": bool(run and run.reached),
                        "replans": run.replans if run else None, "plan_seconds": plan_s,
                        "seconds": time.perf_counter() - t}
    return out


def free_target(model_path: str, seed: int) -> float | None:
    """V 10-25 cm to one side of the start, chosen without simulating any behaviour: the side
    is drawn among those where the perceived footprint stays on the table (None: neither)."""
    from afford import api
    from afford.sim.world import TableConfig

    m = api.load_model(model_path)
    start = api.world("table", seed=seed, objects=1, reachable=True).perceive()
    if start.shape[0] < 1 or not m.schema.visible(start[0]):
        return None
    y0, y1 = float(start[0, m.schema.index("y_min")]), float(start[0, m.schema.index("y_max")])
    half = TableConfig().table_width / 2 - 0.02
    rng = np.random.default_rng(seed)
    d = float(rng.uniform(0.10, 0.25))
    sides = [s for s in (-1.0, 1.0) if -half <= y0 + s * d and y1 + s * d <= half]
    return None if not sides else y0 + float(rng.choice(sides)) * d


def model_target(model_path: str, seed: int) -> float | None:
    """V where the member-effect forward model expects one sideways push's most likely
    outcome to leave the object's ``y_min`` (None: no push is expected to move it 8 cm or
    more and keep it seen on the table)."""
    from afford import api

    m = api.load_model(model_path)
    fm = m.forward(effects="members")
    start = api.world("table", seed=seed, objects=1, reachable=True).perceive()
    if start.shape[0] < 1 or not m.schema.visible(start[0]):
        return None
    iy = m.schema.index("y_min")
    y0 = float(start[0, iy])
    ends = []
    for b in ("push-left", "push-right"):
        outs = fm.outcomes(start, 0, m.names.index(b))
        if outs and m.schema.visible(outs[0].state[0]) and abs(float(outs[0].state[0, iy]) - y0) >= 0.08:
            ends.append(float(outs[0].state[0, iy]))
    return float(np.random.default_rng(seed).choice(ends)) if ends else None


def position_scene(model_path: str, seed: int, targets: str = "sim", effects=EFFECTS) -> dict | None:
    if targets in ("free", "model"):
        v = (free_target if targets == "free" else model_target)(model_path, seed)
        if v is None:
            return None
        row = run_goal(model_path, seed, [f"0:y_min={v:.3f}~0.05"], 1, effects)
        return row and {"seed": seed, "V": v, **row}
    found = reachable(model_path, seed)
    if found is None:
        return None
    y0, ends = found
    rng = np.random.default_rng(seed)
    for _ in range(50):
        v = float(y0 + rng.uniform(-0.3, 0.3))
        if abs(v - y0) > 0.05 and any(abs(e - v) <= 0.05 for e in ends):
            break
    else:
        return None
    row = run_goal(model_path, seed, [f"0:y_min={v:.3f}~0.05"], 1, effects)
    return row and {"seed": seed, "y0": y0, "V": v, **row}


def summary(rows: list[dict], effects=EFFECTS) -> dict:
    out = {"scenes": len(rows)}
    for effect_model in effects:
        r = [x[effect_model] for x in rows]
        found = [x for x in r if x["found"]]
        out[effect_model] = {
            "found": len(found), "reached": sum(x["reached"] for x in r),
            "reached_rate": round(sum(x["reached"] for x in r) / max(1, len(r)), 3),
            # a scene with no plan counts as predicted 0 (and is not reached)
            "mean_predicted": round(float(np.mean([x["p"] if x["found"] else 0.0 for x in r])), 3) if r else None,
            "mean_predicted_found": round(float(np.mean([x["p"] for x in found])), 3) if found else None,
            "reached_rate_found": round(sum(x["reached"] for x in found) / max(1, len(found)), 3),
            "mean_length": round(float(np.mean([x["length"] for x in found])), 2) if found else None,
            "mean_replans": round(float(np.mean([x["replans"] for x in found])), 2) if found else None,
            "plan_seconds": round(float(np.mean([x["plan_seconds"] for x in r])), 3) if r else None,
            "seconds_per_scene": round(float(np.mean([x["seconds"] for x in r])), 2) if r else None,
        }
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model")
    ap.add_argument("--test", help="held-out interactions for the effect error (explored from --seed + 1 if absent)")
    ap.add_argument("--interactions", type=int, default=5000)
    ap.add_argument("--scenes", type=int, default=100)
    ap.add_argument("--clear", type=int, default=30)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--targets", choices=["sim", "free", "model"], default="sim",
                    help="sim: V some push sequence reaches in simulation; free: V drawn without any outcome; "
                         "model: V where the robot's forward model expects one push to leave the object")
    ap.add_argument("--effects", choices=["both", *EFFECTS], default="both")
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "position.json"))
    args = ap.parse_args()
    from joblib import Parallel, delayed

    from benchmarks.plan import build_model

    t = time.perf_counter()
    model_path = args.model or build_model(args.interactions, args.seed)
    build_s = None if args.model else round(time.perf_counter() - t, 1)
    base = 20_000 + 1000 * args.seed
    effects = EFFECTS if args.effects == "both" else (args.effects,)
    pos = [r for r in Parallel(n_jobs=args.workers)(delayed(position_scene)(model_path, base + i, args.targets, effects)
                                                    for i in range(args.scenes)) if r]
    clear = [r for r in Parallel(n_jobs=args.workers)(
        delayed(run_goal)(model_path, base + 500 + i, [f"{j}:visibility=0" for j in range(3)], 3, effects)
        for i in range(args.clear)) if r]

    from afford import api
    from afford.commands.evaluate import effect_error

    test_path = args.test
    if test_path is None:
        test_path = str(Path(tempfile.mkdtemp(prefix="afford-bench-")) / "test.afford")
        api.save(api.explore("table", interactions=1000, seed=args.seed + 1, workers=args.workers), test_path)
    model, data = api.load_model(model_path), api.load_interactions(test_path)
    errors = {name: effect_error(model, name, data, np.flatnonzero(data.behavior == data.behavior_names.index(name)))
              for name in model.names}
    emit({"benchmark": "position", "model_build_seconds": build_s, "model": model_path,
          "k": {n: model.members[n].k_ if model.members[n] is not None else None for n in model.names},
          "targets": args.targets,
          "positioning": summary(pos, effects), "clearing": summary(clear, effects), "effect_error": errors,
          "positioning_rows": pos}, args.out)


if __name__ == "__main__":
    main()
