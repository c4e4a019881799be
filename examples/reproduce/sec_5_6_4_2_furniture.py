"""Thesis 5.6.4.2: tables and a chair, never met in training, judged by a robot that learned among simple objects.

    python examples/reproduce/sec_5_6_4_2_furniture.py [--quick] [--seed S] [--out DIR] [--workers W]
        [--kernel linear|rbf|forest] [--model M] [--episodes N] [--test-episodes M]

The robot learns on ``traverse`` (random boxes, cylinders and spheres, 5.6.1), as
``afford explore | select-features | train`` does, unless ``--model`` gives such a model.
It is then set before furniture built from boxes (``traverse-furniture``, ``sim.furniture``):
a wooden table with 5.5 cm legs, sometimes high enough to drive under; an iron table with
3.5 cm legs and bars joining them at a varied height; a chair with 4 cm legs. Each piece
is placed at random in front of the robot, turned any way, over M environments (seeds
S + 20 + k); in each, every move is tried in PhysX and the robot's own odometry judges it.
The thesis's figures are go-forward's (one object in front of the robot, as 5.6.4.1): 85.5 %
(wooden table, 64.9 % of its test situations not traversable), 81.7 % (iron table, 74.2 %)
and 94.7 % (chair, 68.4 %), over 1000 interactions each.

Full mode: the model from 5000 interactions of seed S and 300 environments per piece;
``--quick``: 100 training and 30 test environments (minutes, for ``make reproduce``).

Writes ``DIR/sec_5_6_4_2_furniture.{md,json,png}``; the JSON's ``rows`` hold one row per
piece: ``furniture``, ``accuracy`` (go-forward), ``not_traversable`` (the share of its test
situations where go-forward failed), ``majority`` (the accuracy of always answering the
commoner result), ``all_moves`` (accuracy over the seven moves), ``n_test`` and ``thesis``
(``accuracy`` and ``not_traversable``).
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

NAME = "sec_5_6_4_2_furniture"
TRAIN_SCENE = "traverse"
SCENE = "traverse-furniture"
BEHAVIOR = "go-forward"
#: The thesis's figures (5.6.4.2): accuracy and the share of non-traversable test situations.
THESIS = {"wooden-table": (0.855, 0.649), "iron-table": (0.817, 0.742), "chair": (0.947, 0.684)}


def score(model, data) -> dict:
    """Go-forward's and every move's accuracy on ``data``, and go-forward's failure share."""
    hits, total, forward = 0, 0, None
    for b, name in enumerate(data.behavior_names):
        rows = np.flatnonzero(data.behavior == b)
        y = data.result[rows].astype(int)
        right = model.predict(name, data.before_rows(rows)) == y
        hits, total = hits + int(right.sum()), total + rows.size
        if name == BEHAVIOR:
            forward = {"accuracy": round(float(right.mean()), 4), "not_traversable": round(float(1 - y.mean()), 4),
                       "majority": round(float(max(y.mean(), 1 - y.mean())), 4), "n_test": int(rows.size)}
    return {**forward, "all_moves": round(hits / total, 4)}


def run(args, model_path: str) -> list[dict]:
    import afford
    from afford.sim.furniture import KINDS

    model = afford.load_model(model_path)
    missing = [b.name for b in afford.make_scene(SCENE).behaviors if b.name not in model.predictors]
    if missing:
        sys.exit(f"error: the model has no predictor for {', '.join(missing)}; give a model trained on {TRAIN_SCENE}")
    n = args.test_episodes or (30 if args.quick else 300)
    rows = []
    for k, kind in enumerate(KINDS):
        data = afford.explore(SCENE, episodes=n, seed=args.seed + 20 + k, workers=args.workers, furniture=kind)
        rows.append({"furniture": kind, **score(model, data),
                     "thesis": {"accuracy": THESIS[kind][0], "not_traversable": THESIS[kind][1]}})
    return rows


def write(doc: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    pct = lambda v: f"{100 * v:.1f} %"  # noqa: E731
    lines = ["# Complex objects: tables and a chair never met in training (thesis 5.6.4.2)", "",
             f"Trained on `{TRAIN_SCENE}` ({doc['trained_on']}), tested on `{SCENE}`: seed {doc['seed']}, commit "
             f"{doc['commit']}, {'quick' if doc['quick'] else 'full'} mode, {doc['rows'][0]['n_test']} situations per piece.", "",
             "| piece | go-forward accuracy | thesis | not traversable | thesis | always the commoner result | all seven moves |",
             "|---|---|---|---|---|---|---|"]
    lines += [f"| {r['furniture']} | {pct(r['accuracy'])} | {pct(r['thesis']['accuracy'])} | {pct(r['not_traversable'])} | "
              f"{pct(r['thesis']['not_traversable'])} | {pct(r['majority'])} | {pct(r['all_moves'])} |" for r in doc["rows"]]
    lines += ["", "Each piece is fixed boxes (`sim.furniture`); the robot never met furniture while it learned."]
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    _figure(doc, out / f"{NAME}.png")


def _figure(doc: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    rows = doc["rows"]
    x = np.arange(len(rows))
    fig, ax = plt.subplots(figsize=(6.5, 4))
    ax.bar(x - 0.27, [r["accuracy"] for r in rows], 0.27, label="afford, go-forward")
    ax.bar(x, [r["thesis"]["accuracy"] for r in rows], 0.27, label="thesis")
    ax.bar(x + 0.27, [r["majority"] for r in rows], 0.27, label="always the commoner result", color="0.7")
    ax.set_xticks(x, [r["furniture"] for r in rows])
    ax.set_ylim(0, 1)
    ax.set_ylabel("prediction accuracy")
    ax.set_title("Furniture never met in training (thesis 5.6.4.2)")
    ax.legend(loc="lower right", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = parser(__doc__)
    learner_option(ap)
    ap.add_argument("--model", default=None, help=f"a model trained on {TRAIN_SCENE}: skip exploring and learning")
    ap.add_argument("--episodes", type=int, default=None, help="training environments (default: 5000 interactions; quick 100)")
    ap.add_argument("--test-episodes", type=int, default=None, help="test environments per piece (default 300; quick 30)")
    args = ap.parse_args()
    for flag, v in (("--episodes", args.episodes), ("--test-episodes", args.test_episodes)):
        if v is not None and v < 2:
            sys.exit(f"error: {flag} must be at least 2, got {v}")
    if args.model is not None and not Path(args.model).is_file():
        sys.exit(f"error: no model file {args.model}")
    from afford.errors import AffordError
    from afford.features.errors import DataError

    try:
        with tempfile.TemporaryDirectory() as tmp:
            model_path = args.model or train_model(TRAIN_SCENE, args, Path(tmp))
            rows = run(args, model_path)
    except (AffordError, DataError) as exc:
        sys.exit(f"error: {exc}")
    trained = (f"model {args.model}" if args.model else
               f"{args.episodes} environments" if args.episodes else "100 environments" if args.quick else "5000 interactions"
               ) + learner_note(args)
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, "trained_on": trained, "rows": rows}
    write(doc, Path(args.out))
    print((Path(args.out) / f"{NAME}.md").read_text())


if __name__ == "__main__":
    main()
