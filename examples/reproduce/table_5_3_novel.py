"""Thesis Table 5.3: do learned affordances carry over to objects never met in training?

    python examples/reproduce/table_5_3_novel.py [--quick] [--seed S] [--out DIR] [--workers W]
        [--episodes N] [--test-episodes M]

As the thesis (5.6.4.1): every environment holds one object in front of the robot and
go-forward is what is judged. Per shape (box, cylinder, lying-cylinder, sphere) the robot
explores ``traverse-one`` with only that shape, once to learn from (seed S + k) and once to
test on (seed S + 10 + k). Each of the 15 non-empty subsets of the shapes (the thesis's
cases, in its order: the single shapes, the pairs, the triples, all four) trains on N
go-forward interactions drawn evenly from its shapes' pools (N / |subset| of each, so every
case learns from as many interactions), chapter 5's way: ReliefF with its cross-validated
cut, then the linear SVM with C by 5-fold cross-validation. Each case is tested on each
shape's test pool alone.

Full mode: 300 training and 150 test environments per shape; ``--quick``: 40 and 20.

The thesis's icons are lost from our copy of Table 5.3; its text fixes the columns: the
fourth is the sphere ("spheres are predicted to be traversable with 30 % accuracy" in cases
2 and 3, and case 4 "includes only traversable objects"), the first the lying cylinder (case
1's shape "can be traversable or non-traversable, depending on its relative orientation").
That the second is the box and the third the upright cylinder is our assumption; both block.

Writes ``DIR/table_5_3_novel.{md,json,png}``; the JSON's ``rows`` hold one row per case and
test shape: ``case``, ``train`` (shapes), ``test`` (shape), ``novel`` (the test shape was
not in training), ``accuracy``, ``traversable`` (the test pool's share of successes),
``n_test`` and ``thesis``.
"""

from __future__ import annotations

import itertools
import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, parser  # noqa: E402

NAME = "table_5_3_novel"
SCENE = "traverse-one"
BEHAVIOR = "go-forward"
#: The thesis's column order, as its text fixes it (see the module docstring).
SHAPES = ("lying-cylinder", "box", "cylinder", "sphere")
#: Table 5.3, the thesis's prediction accuracy (%), per case (rows) and test shape (columns, SHAPES).
THESIS = ((96, 95, 86, 100), (66, 97, 94, 31), (75, 98, 99, 30), (55, 30, 34, 100),
          (96, 98, 91, 88), (97, 98, 96, 80), (95, 83, 78, 100), (70, 97, 97, 30),
          (93, 93, 86, 100), (95, 93, 91, 100), (95, 98, 93, 81), (97, 92, 87, 100),
          (95, 98, 94, 100), (95, 96, 90, 100), (95, 97, 92, 100))
#: The 15 cases, in the thesis's order.
CASES = tuple(c for n in range(1, 5) for c in itertools.combinations(SHAPES, n))


def go_forward(data) -> tuple[np.ndarray, np.ndarray]:
    """The go-forward rows' features and the robot's results (1: success)."""
    rows = np.flatnonzero(data.behavior == data.behavior_names.index(BEHAVIOR))
    return data.before_rows(rows), data.result[rows].astype(int)


def explore_pools(args, episodes: int, offset: int) -> dict:
    from afford.sim.explore import explore
    from afford.sim.registry import make_scene

    return {s: go_forward(explore(make_scene(SCENE, shapes=(s,)), episodes=episodes, seed=args.seed + offset + k,
                                  workers=args.workers))
            for k, s in enumerate(SHAPES)}


def learn(X: np.ndarray, y: np.ndarray, seed: int):
    """Chapter 5's learner on one behaviour's rows: ReliefF's cut, then the calibrated linear SVM."""
    from afford.learn.affordances import prefix_estimator
    from afford.learn.predictors import AffordancePredictor
    from afford.learn.relevance import FeatureRelevance

    if np.unique(y).size < 2:  # one result only (spheres always roll away): nothing to tell apart
        value = int(y[0])
        return None, lambda Z: np.full(len(Z), value)
    fr = FeatureRelevance(method="relieff", random_state=seed, estimator=prefix_estimator("linear")).fit(X, y)
    keep = np.asarray(fr.selected_, dtype=int)
    model = AffordancePredictor(kernel="linear", cv=5, random_state=seed).fit(X[:, keep], y)
    return keep, lambda Z: model.predict(Z[:, keep])


def run(args) -> list[dict]:
    n_train, n_test = (40, 20) if args.quick else (300, 150)
    n_train, n_test = args.episodes or n_train, args.test_episodes or n_test
    train, test = explore_pools(args, n_train, 0), explore_pools(args, n_test, 10)
    rows = []
    for c, case in enumerate(CASES):
        per = n_train // len(case)
        X = np.vstack([train[s][0][:per] for s in case])
        y = np.concatenate([train[s][1][:per] for s in case])
        keep, predict = learn(X, y, args.seed + c)
        for j, s in enumerate(SHAPES):
            Xt, yt = test[s]
            rows.append({"case": c + 1, "train": list(case), "test": s, "novel": s not in case,
                         "accuracy": round(float(np.mean(predict(Xt) == yt)), 4),
                         "traversable": round(float(yt.mean()), 4), "n_test": int(yt.size),
                         "features_kept": None if keep is None else int(keep.size), "thesis": THESIS[c][j] / 100})
    return rows


def summary(rows: list[dict]) -> dict:
    def mean(key, sel):
        v = [r[key] for r in rows if sel(r)]
        return round(float(np.mean(v)), 4)

    return {"novel": mean("accuracy", lambda r: r["novel"]), "seen": mean("accuracy", lambda r: not r["novel"]),
            "all_four": mean("accuracy", lambda r: r["case"] == 15),
            "thesis_novel": mean("thesis", lambda r: r["novel"]), "thesis_seen": mean("thesis", lambda r: not r["novel"]),
            "thesis_all_four": mean("thesis", lambda r: r["case"] == 15),
            "mean_abs_difference": round(float(np.mean([abs(r["accuracy"] - r["thesis"]) for r in rows])), 4),
            "traversable": {s: next(r["traversable"] for r in rows if r["test"] == s) for s in SHAPES}}


def write(doc: dict, out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    s, rows = doc["summary"], doc["rows"]
    head = " | ".join(SHAPES)
    lines = ["# Table 5.3: learned affordances on novel objects (thesis 5.6.4.1)", "",
             f"Scene `{SCENE}` (one object, go-forward), seed {doc['seed']}, commit {doc['commit']}, "
             f"{'quick' if doc['quick'] else 'full'} mode: {doc['episodes']} training environments per case, "
             f"{doc['test_episodes']} test environments per shape. Each cell: ours (the thesis's), % correct; "
             "*italic*: a shape the case never met in training.", "",
             f"| case | trained on | {head} |", "|---|---|" + "---|" * len(SHAPES)]
    for c in range(1, len(CASES) + 1):
        cells = [r for r in rows if r["case"] == c]
        fmt = ["{}{:.0f} ({:.0f}){}".format("*" if r["novel"] else "", 100 * r["accuracy"], 100 * r["thesis"],
                                            "*" if r["novel"] else "") for r in cells]
        lines.append(f"| {c} | {', '.join(cells[0]['train'])} | " + " | ".join(fmt) + " |")
    trav = ", ".join(f"{k} {100 * v:.0f} %" for k, v in s["traversable"].items())
    lines += ["", f"Mean accuracy on shapes never met in training {100 * s['novel']:.1f} % (thesis "
              f"{100 * s['thesis_novel']:.1f} %), on shapes met {100 * s['seen']:.1f} % ({100 * s['thesis_seen']:.1f} %); "
              f"case 15, all four, {100 * s['all_four']:.1f} % ({100 * s['thesis_all_four']:.1f} %). Mean absolute "
              f"difference from the thesis's cells: {100 * s['mean_abs_difference']:.1f} points.",
              "", f"Go-forward succeeded in the test pools: {trav}.",
              "", "The thesis's columns are read from its text (its icons are lost from our copy); that its "
              "second is the box and its third the upright cylinder is our assumption."]
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    _figure(doc, out / f"{NAME}.png")


def _figure(doc: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(9, 6), sharey=True)
    n = len(CASES)
    for ax, key, title in ((axes[0], "accuracy", "afford (PhysX)"), (axes[1], "thesis", "thesis Table 5.3")):
        grid = np.array([[r[key] for r in doc["rows"] if r["case"] == c] for c in range(1, n + 1)])
        ax.imshow(grid, vmin=0.0, vmax=1.0, cmap="viridis", aspect="auto")
        for (i, j), v in np.ndenumerate(grid):
            novel = SHAPES[j] not in CASES[i]
            ax.text(j, i, f"{100 * v:.0f}", ha="center", va="center", fontsize=8,
                    color="white" if v < 0.6 else "black", fontweight="normal" if novel else "bold")
        ax.set_xticks(range(len(SHAPES)), [s.replace("-", "-\n") for s in SHAPES], fontsize=8)
        ax.set_title(title)
    axes[0].set_yticks(range(n), [f"{c + 1}: " + "+".join(s[:4] for s in case) for c, case in enumerate(CASES)], fontsize=7)
    fig.suptitle("Go-forward accuracy by training shapes (rows) and test shape (columns); bold: seen in training")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main() -> None:
    ap = parser(__doc__)
    ap.add_argument("--episodes", type=int, default=None, help="training environments per case (default 300; quick 40)")
    ap.add_argument("--test-episodes", type=int, default=None, help="test environments per shape (default 150; quick 20)")
    args = ap.parse_args()
    for flag, v in (("--episodes", args.episodes), ("--test-episodes", args.test_episodes)):
        if v is not None and v < 8:
            sys.exit(f"error: {flag} must be at least 8, got {v}")
    rows = run(args)
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, "scene": SCENE,
           "behavior": BEHAVIOR, "episodes": args.episodes or (40 if args.quick else 300),
           "test_episodes": args.test_episodes or (20 if args.quick else 150), "rows": rows, "summary": summary(rows)}
    write(doc, Path(args.out))
    print((Path(args.out) / f"{NAME}.md").read_text())


if __name__ == "__main__":
    main()
