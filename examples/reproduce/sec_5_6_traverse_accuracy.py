"""Thesis 5.6.1-5.6.2: how well the mobile robot predicts traversability, per scene and move.

    python examples/reproduce/sec_5_6_traverse_accuracy.py [--quick] [--seed S] [--out DIR] [--scenes a,b]

The thesis reports prediction success of about 87 % in random clutter (5.6.1), 90 % with
hanging boxes (5.6.2.1), 95 % with ramps (5.6.2.2) and 95 % with gaps (5.6.2.3). For each
traverse scene this explores a training and a test set (seeds S and S + 1), learns as
``afford select-features | afford train`` does (ReliefF with its cross-validated cut, the
scene's linear SVM), and scores each move on the test set beside a random forest trained
on the same features. Full mode: 5000 training and 1400 test interactions per scene, as the
README's figures; ``--quick``: 100 and 20 environments (minutes, for ``make reproduce``, whose
``--cache`` shares the training sets and models with the scripts of figure 5.5 and tables 5.1
and 5.2, which learn from the same ones).

Writes ``DIR/sec_5_6_traverse_accuracy.{md,json,png}``; the JSON's ``rows`` hold one row per
scene and move: ``scene``, ``behavior``, ``accuracy``, ``random_forest``, ``majority``,
``n_test``, ``features_kept``, and ``thesis`` (the scene's figure; the thesis gives one per
scene, not per move).
"""

from __future__ import annotations

import json
import sys
import tempfile
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, explored, parser, train_model  # noqa: E402

NAME = "sec_5_6_traverse_accuracy"
#: The thesis's figures (5.6.1 and 5.6.2), quoted from its text.
THESIS = {"traverse": 0.87, "traverse-body": 0.90, "traverse-ramps": 0.95, "traverse-gaps": 0.95}
SECTION = {"traverse": "5.6.1", "traverse-body": "5.6.2.1", "traverse-ramps": "5.6.2.2", "traverse-gaps": "5.6.2.3"}


def scene_rows(name: str, args) -> list[dict]:
    """The scene's model (``train_model``: explored, ``select-features``, ``train``) scored on
    held-out environments of seed S + 1, as ``afford evaluate --baselines`` scores it."""
    from afford.commands.evaluate import evaluate_model

    import afford

    with tempfile.TemporaryDirectory() as tmp:
        model = afford.load_model(train_model(name, args, Path(tmp)))
    test = explored(name, args, seed=args.seed + 1, **({"episodes": 20} if args.quick else {"interactions": 1400}))
    rows = []
    for behavior, e in evaluate_model(model, test, baselines=True, seed=args.seed).items():
        base = e["baselines"]
        rows.append({"scene": name, "behavior": behavior, "accuracy": round(float(e["accuracy"]), 4),
                     "random_forest": round(float(base["random_forest"]), 4), "majority": round(float(base["majority"]), 4),
                     "n_test": int(e["n_test"]), "features_kept": int(len(model.selected[behavior])), "thesis": THESIS[name]})
    return rows


def write(rows: list[dict], args) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    means = {s: float(np.mean([r["accuracy"] for r in rows if r["scene"] == s])) for s in scenes}
    forest = {s: float(np.mean([r["random_forest"] for r in rows if r["scene"] == s])) for s in scenes}
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, "rows": rows,
           "scenes": {s: {"mean_accuracy": round(means[s], 4), "random_forest": round(forest[s], 4),
                          "thesis": THESIS[s]} for s in scenes}}
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    lines = [f"# Traversability prediction (thesis {', '.join(SECTION[s] for s in scenes)})", "",
             f"Seed {args.seed}, commit {doc['commit']}, {'quick' if args.quick else 'full'} mode.", "",
             "| scene | ours (mean over the 7 moves) | thesis | random forest, same features |", "|---|---|---|---|"]
    lines += [f"| `{s}` | {100 * means[s]:.1f} % | {100 * THESIS[s]:.0f} % | {100 * forest[s]:.1f} % |" for s in scenes]
    lines += ["", "| scene | move | ours | random forest | majority | test rows | features kept |",
              "|---|---|---|---|---|---|---|"]
    lines += [f"| `{r['scene']}` | {r['behavior']} | {100 * r['accuracy']:.1f} % | {100 * r['random_forest']:.1f} % | "
              f"{100 * r['majority']:.1f} % | {r['n_test']} | {r['features_kept']} |" for r in rows]
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(1.6 + 1.4 * len(scenes), 3.2))
    x = np.arange(len(scenes))
    ax.bar(x - 0.2, [100 * means[s] for s in scenes], 0.4, label="afford", color="#3b7dd8")
    ax.bar(x + 0.2, [100 * THESIS[s] for s in scenes], 0.4, label="thesis", color="#bbbbbb")
    ax.set_xticks(x, scenes)
    ax.set_ylim(50, 100)
    ax.set_ylabel("prediction accuracy (%)")
    ax.legend(loc="lower right")
    fig.tight_layout()
    fig.savefig(out / f"{NAME}.png", dpi=110)
    print("\n".join(lines[:6 + len(scenes)]))


def main() -> None:
    ap = parser(__doc__)
    ap.add_argument("--scenes", default=",".join(THESIS))
    ap.add_argument("--episodes", type=int, default=None,
                    help="training environments per scene (default: 5000 interactions; quick 100)")
    args = ap.parse_args()
    names = [s for s in args.scenes.split(",") if s]
    unknown = [s for s in names if s not in THESIS]
    if unknown:
        sys.exit(f"error: {unknown[0]!r} is not a traverse scene; choose from {', '.join(THESIS)}")
    from afford import AffordError
    from afford.features.errors import DataError

    try:
        rows = [r for name in names for r in scene_rows(name, args)]
    except (AffordError, DataError) as exc:  # e.g. a quick run in which a move never failed
        sys.exit(f"error: {exc}")
    write(rows, args)


if __name__ == "__main__":
    main()
