"""Thesis 5.6.5 (Figures 5.9-5.11): the trained robot drives through furnished rooms, aggressive, cautious and random.

    python examples/reproduce/sec_5_6_5_navigation.py [--quick] [--seed S] [--out DIR] [--workers W]
        [--train-scene traverse-room|traverse] [--kernel linear|rbf|forest] [--model M] [--episodes N]
        [--rooms K] [--steps N]

The robot learns on ``--train-scene`` as ``afford explore | select-features | train`` does,
unless ``--model`` gives such a model, and is then driven by ``afford navigate`` in K rooms
of the ``room`` scene (seeds 0..K-1: walls, tables and chairs it never met, loose objects),
once per controller: aggressive and cautious (Figure 5.9) and random (the baseline). A run
ends after N steps or when the robot is stuck (three failed moves in a row, or a whole turn
of looking around with nothing afforded; after a failed move the robot does not try a
heading that failed since its last success). The thesis shows paths (Figures 5.10, 5.11)
and argues that the cautious controller risks fewer collisions; it gives no numbers.

The default training scene is ``traverse-room`` (chapter 6's world): the robot at random
places and headings in one walled 6 x 6 m room of 30 loose simple objects of 20-40 cm, a room
other than those it is driven in. The thesis trained on the simple objects alone
(``traverse``, still available); a robot that never met a wall takes it for open floor, since
nothing in its experience links a near, flat, tall surface with a failed move, and a share
of its failed moves are at the room's walls. Either way the tables and chairs are never seen in
training.

The learner is a random forest on all 3900 grid features (``--kernel forest``; ours, not the
thesis's), unless ``--kernel`` names another: ``linear`` is the scene's, the thesis's linear
SVM on ReliefF's cut. The forest drives further: over training seeds 1-3 its aggressive
controller went 7.0-8.7 times as far as the random one, where the linear SVM went 5.6 and 3.8
times (seeds 1 and 2). It learns 5000 interactions in about a minute, choosing its leaf size
and calibration on out-of-bag votes.

Full mode: the model from 5000 interactions of seed S, 10 rooms, 100 steps; ``--quick``:
100 training environments, 3 rooms, 30 steps.

Writes ``DIR/sec_5_6_5_navigation.{md,json,png}``; the JSON's ``rows`` hold one row per room
and controller (``room``, ``controller``, ``distance_m``, ``moves``, ``failed_moves``,
``failed_per_metre``, ``stuck``) and ``summary`` per controller the mean distance, the
failed moves per metre over all its runs, how many runs ended stuck, and the mean distance
against the random controller's.
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, learner_note, learner_option, parser, train_model  # noqa: E402

NAME = "sec_5_6_5_navigation"
CONTROLLERS = ("aggressive", "cautious", "random")


def one_run(model_path: str, room: int, controller: str, steps: int) -> dict:
    import afford

    return afford.navigate(model_path, scene="room", controller=controller, seed=room, steps=steps)


def summary(rows: list[dict]) -> dict:
    out = {}
    for c in CONTROLLERS:
        r = [x for x in rows if x["controller"] == c]
        metres = sum(x["distance_m"] for x in r)
        out[c] = {"mean_distance_m": round(float(np.mean([x["distance_m"] for x in r])), 3),
                  "failed_per_metre": round(sum(x["failed_moves"] for x in r) / metres, 4) if metres else None,
                  "stuck": sum(bool(x["stuck"]) for x in r), "runs": len(r)}
    base = out["random"]["mean_distance_m"]
    for c in CONTROLLERS:
        out[c]["times_random"] = round(out[c]["mean_distance_m"] / base, 2) if base > 0 else None
    return out


def write(doc: dict, runs: list[dict], out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    s = doc["summary"]
    lines = ["# Navigation in furnished rooms (thesis 5.6.5, Figures 5.9-5.11)", "",
             f"Trained on {doc['trained_on']}, driven in `room` 0-{doc['rooms'] - 1}: seed {doc['seed']}, "
             f"commit {doc['commit']}, {'quick' if doc['quick'] else 'full'} mode, at most {doc['steps']} steps a run.", "",
             "| controller | mean distance | against random | failed moves per metre | runs ended stuck |", "|---|---|---|---|---|"]
    for c in CONTROLLERS:
        fpm = "-" if s[c]["failed_per_metre"] is None else f"{s[c]['failed_per_metre']:.2f}"
        times = "-" if s[c]["times_random"] is None else f"{s[c]['times_random']:.1f} x"
        lines.append(f"| {c} | {s[c]['mean_distance_m']:.2f} m | {times} | {fpm} | {s[c]['stuck']} of {s[c]['runs']} |")
    lines += ["", "The thesis gives paths, not numbers: it argues the cautious controller risks fewer collisions "
              "than the aggressive one. A run ends stuck after three failed moves in a row (or a whole turn with "
              "nothing afforded); a heading that failed is not tried again before a move succeeds."]
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    _figure(runs, out / f"{NAME}.png")


def _figure(runs: list[dict], path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    import afford
    from afford.navigation import draw_navigation

    # room 0 for each controller, side by side: one PNG per run, pasted into one figure
    first = [r for r in runs if r["room"] == 0]
    fig, axes = plt.subplots(1, len(first), figsize=(5 * len(first), 5))
    with tempfile.TemporaryDirectory() as tmp:
        for ax, r in zip(np.atleast_1d(axes), first):
            png = draw_navigation(str(Path(tmp) / f"{r['controller']}.png"), afford.make_scene("room", room=0), r)
            ax.imshow(plt.imread(png))
            ax.axis("off")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = parser(__doc__)
    ap.add_argument("--train-scene", default="traverse-room", choices=("traverse-room", "traverse"),
                    help="where the robot learns (default traverse-room: the simple objects inside walls)")
    learner_option(ap, default="forest")
    ap.add_argument("--model", default=None, help="a model trained on a traverse scene: skip exploring and learning")
    ap.add_argument("--episodes", type=int, default=None, help="training environments (default: 5000 interactions; quick 100)")
    ap.add_argument("--rooms", type=int, default=None, help="rooms (seeds 0..K-1; default 10, quick 3)")
    ap.add_argument("--steps", type=int, default=None, help="most steps a run (default 100, quick 30)")
    args = ap.parse_args()
    rooms = args.rooms or (3 if args.quick else 10)
    steps = args.steps or (30 if args.quick else 100)
    if rooms < 1 or steps < 1:
        sys.exit("error: --rooms and --steps must be at least 1")
    if args.model is not None and not Path(args.model).is_file():
        sys.exit(f"error: no model file {args.model}")
    from joblib import Parallel, delayed

    from afford.errors import AffordError
    from afford.features.errors import DataError

    try:
        with tempfile.TemporaryDirectory() as tmp:
            model_path = args.model or train_model(args.train_scene, args, Path(tmp))
            runs = Parallel(n_jobs=args.workers)(delayed(one_run)(model_path, room, c, steps)
                                                 for room in range(rooms) for c in CONTROLLERS)
    except (AffordError, DataError) as exc:
        sys.exit(f"error: {exc}")
    keys = ("room", "controller", "distance_m", "moves", "failed_moves", "failed_per_metre", "stuck")
    rows = [{k: r[k] for k in keys} for r in runs]
    trained = (f"model {args.model}" if args.model else f"`{args.train_scene}`, " + (
        f"{args.episodes} environments" if args.episodes else "100 environments" if args.quick else "5000 interactions")
    ) + learner_note(args)
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, "trained_on": trained,
           "rooms": rooms, "steps": steps, "rows": rows, "summary": summary(rows)}
    write(doc, runs, Path(args.out))
    print((Path(args.out) / f"{NAME}.md").read_text())


if __name__ == "__main__":
    main()
