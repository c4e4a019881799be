"""Beyond thesis chapter 6: curiosity over discovered effect categories, at the table.

    python examples/reproduce/sec_6_curiosity_table.py [--quick] [--seed S] [--out DIR] [--workers K]

Chapter 6 made the robot curious about results it was given (traversable or not). Here
the chapter-8 hand is curious about effect categories it discovers itself: each
candidate is one random object on the table (what Algorithm 5's episode of that number
puts there), looked at once; the first ``bootstrap`` candidates are all tried and their
effects clustered once, with the scene's clustering (as ``afford cluster`` does), into
the categories every later effect is named by (the nearest one); after that the robot
tries a candidate only when the entropy of the calibrated probabilities its RBF SVM
gives over those categories is high (``afford explore --scene table --strategy
entropy``). Every candidate's effect under every behaviour is run once in PhysX up
front, so the orderings replay one stream: a strategy only ever learns the effects of
the candidates it tries. The test set is another seed's candidates, every behaviour
tried on each, named by the same categories.

The figure is a learning curve per behaviour: test accuracy against the interactions
tried, for random exploration (every candidate) and for curiosity (the margin, entropy
with a budget of a third of the candidates and with the 0.7 threshold, the committee),
medians and quartiles over the orderings, at equal interactions. The thesis has no such
figure (its chapter 6 is go-forward's given results); ``thesis`` is null.

A diagnosis beside it: the same strategies learning the world's own outcome labels
(fell, left view, lifted, dragged, no change: ground truth, which the robot never learns
from) instead of the discovered categories, to tell the categories' part in what
curiosity gains from the table's.

Full mode: 1500 candidates, 600 test objects, 10 orderings; ``--quick``: 300, 150, 3 (its
checkpoints end at 150 interactions).

Writes ``DIR/sec_6_curiosity_table.{md,json,png}``; the JSON's ``rows`` hold one row per
labels, behaviour, strategy and checkpoint: ``labels`` ("discovered", or "outcome" for
the diagnosis), ``behavior``, ``strategy``, ``interactions``, ``median``, ``q1``, ``q3``
(test accuracy over the orderings, ``n`` of them), ``tried`` (interactions the strategy had tried by
then, median) and ``thesis`` (null).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, quartiles, stream_parser  # noqa: E402

NAME = "sec_6_curiosity_table"
CHECKPOINTS = {True: (50, 100, 150), False: (50, 100, 200, 300, 500)}  # quick, full
STRATEGIES = ("random", "margin", "entropy-budget", "entropy", "committee")
BOOTSTRAP = 50
LABELS = ("discovered", "outcome")


def _chunk(scene, seed: int, candidates: list[int]) -> list[tuple]:
    from afford.sim.explore import scan_candidate, try_candidate_effect

    out = []
    for c in candidates:
        look = scan_candidate(scene, seed, c)
        if not np.isfinite(look).all():
            continue  # no object in view: not a situation
        rows = [try_candidate_effect(scene, seed, c, b) for b in range(len(scene.behaviors))]
        out.append((c, look, np.stack([r.effects_of(np.zeros(1, dtype=int))[0] for r in rows]),
                    np.array([int(r.truth["outcome"][0]) for r in rows])))
    return out


def stream(scene, n: int, seed: int, workers: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """n candidates' looks (those with an object in view), every behaviour's effect on each
    (run in PhysX) and the world's outcome label of each (ground truth, for the diagnosis)."""
    from joblib import Parallel, delayed

    chunks = [list(range(a, min(a + 50, n))) for a in range(0, n, 50)]
    parts = [r for part in Parallel(n_jobs=workers)(delayed(_chunk)(scene, seed, c) for c in chunks) for r in part]
    parts.sort(key=lambda p: p[0])
    return tuple(np.stack([p[k] for p in parts]) for k in (1, 2, 3))


def at(curve: list[dict], k: int) -> tuple[float, int]:
    """Test accuracy once ``k`` interactions were tried (the last point at or before k), and how many."""
    points = [c for c in curve if c["interactions"] <= k] or curve[:1]
    return points[-1]["accuracy"], points[-1]["interactions"]


def run(args) -> dict:
    from joblib import Parallel, delayed

    from afford.curiosity import categoriser
    from afford.learn.online import learn_online
    from afford.learning import clustering_settings
    from afford.sim.registry import make_scene

    n, t, orderings = (300, 150, 3) if args.quick else (1500, 600, 10)
    n, t, orderings = args.candidates or n, args.test_size or t, args.orderings or orderings
    scene = make_scene("table")
    X, E, Y = stream(scene, n, args.seed, args.workers)
    Xt, Et, Yt = stream(scene, t, args.seed + 1, args.workers)
    names = [b.name for b in scene.behaviors]
    clustering = clustering_settings(scene.describe(), scene.schema, "the table scene")
    perms = [np.random.default_rng(args.seed * 100 + o).permutation(len(X)) for o in range(orderings)]
    budget = max(len(X) // 3, BOOTSTRAP + 20)  # the budget counts the bootstrap

    def curve(labels: str, strategy: str, b: int, o: int):
        p = perms[o]
        kind = strategy.split("-")[0]
        common = dict(bootstrap=BOOTSTRAP, kernel="rbf", budget=budget if strategy == "entropy-budget" else None,
                      X_test=Xt, every=10, seed=o)
        if labels == "outcome":
            return learn_online(X[p], Y[p, b], kind, y_test=Yt[:, b], **common).curve, None
        categorise, found = categoriser(scene, clustering, b, args.seed, X[p])
        run = learn_online(X[p], E[p, b], kind, categorise=categorise, y_test=list(Et[:, b]), **common)
        return run.curve, int(found["categories"].n_categories_)

    jobs = [(lab, s, b, o) for lab in LABELS for s in STRATEGIES for b in range(len(names)) for o in range(orderings)]
    results = Parallel(n_jobs=args.workers)(delayed(curve)(*j) for j in jobs)
    by: dict = {}
    for (lab, s, b, o), (c, k) in zip(jobs, results):
        by.setdefault((lab, b, s), []).append((c, k))
    rows = []
    for (lab, b, s), runs in by.items():
        base = {"labels": lab, "behavior": names[b], "strategy": s}
        for k in CHECKPOINTS[args.quick]:
            accs, tried = zip(*(at(c, k) for c, _ in runs))
            rows.append({**base, "interactions": k, **quartiles(accs), "tried": int(np.median(tried)), "thesis": None})
        last = [c[-1] for c, _ in runs]
        rows.append({**base, "interactions": "end", **quartiles([c["accuracy"] for c in last]),
                     "tried": int(np.median([c["interactions"] for c in last])), "thesis": None})
    categories = {names[b]: sorted({k for _, k in by[("discovered", b, "random")]}) for b in range(len(names))}
    curves = {f"{lab}|{names[b]}|{s}": [c for c, _ in runs] for (lab, b, s), runs in by.items()}
    return {"rows": rows, "candidates": int(len(X)), "test": int(len(Xt)), "orderings": orderings,
            "bootstrap": BOOTSTRAP, "budget": budget, "n_categories": categories, "curves": curves}


def write(doc: dict, args) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, **doc}
    curves = doc.pop("curves")
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    rows = doc["rows"]
    names = list(dict.fromkeys(r["behavior"] for r in rows))
    checkpoints = CHECKPOINTS[args.quick]
    cell = lambda r: f"{100 * r['median']:.1f} % ({100 * r['q1']:.0f}-{100 * r['q3']:.0f}; {r['tried']})"
    lines = ["# Curiosity over discovered effect categories at the table (beyond thesis chapter 6)", "",
             f"Seed {args.seed}, commit {doc['commit']}, {'quick' if args.quick else 'full'} mode: "
             f"{doc['candidates']} candidate objects, {doc['test']} test objects (seed {args.seed + 1}), "
             f"{doc['orderings']} orderings, a bootstrap of {doc['bootstrap']} clustered into the categories "
             f"(per behaviour, over the orderings: "
             + ", ".join(f"{n} {'/'.join(map(str, k))}" for n, k in doc["n_categories"].items())
             + f"); entropy-budget tries at most {doc['budget']}. The thesis has no such figure.", "",
             "Median test accuracy (quartiles; interactions tried by then) at equal interactions.", ""]
    for lab in LABELS:
        lines += [f"## {'Discovered categories' if lab == 'discovered' else 'Diagnosis: the world outcome labels'}", ""]
        for name in names:
            lines += [f"### {name}", "", "| strategy | " + " | ".join(str(k) for k in checkpoints) + " | at the end |",
                      "|---|" + "---|" * (len(checkpoints) + 1)]
            for s in STRATEGIES:
                cells = [r for r in rows if r["labels"] == lab and r["behavior"] == name and r["strategy"] == s]
                lines.append(f"| {s} | " + " | ".join(cell(r) for r in cells) + " |")
            lines.append("")
    (out / f"{NAME}.md").write_text("\n".join(lines))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(len(LABELS), len(names), figsize=(3.4 * len(names), 3.2 * len(LABELS)), sharey="row",
                             squeeze=False)
    colours = {"random": "#888888", "margin": "#7570b3", "entropy-budget": "#3b7dd8", "entropy": "#1b9e77",
               "committee": "#d95f02"}
    for i, lab in enumerate(LABELS):
        for ax, name in zip(axes[i], names):
            for s in STRATEGIES:
                runs = curves[f"{lab}|{name}|{s}"]
                grid = np.arange(doc["bootstrap"], max(c[-1]["interactions"] for c in runs) + 1, 10)
                acc = np.array([[at(c, k)[0] for k in grid] for c in runs])
                ax.plot(grid, 100 * np.median(acc, axis=0), color=colours[s], label=s)
                ax.fill_between(grid, 100 * np.percentile(acc, 25, axis=0), 100 * np.percentile(acc, 75, axis=0),
                                color=colours[s], alpha=0.15)
            ax.set_title(name if lab == "discovered" else f"{name} (outcome labels)", fontsize=10)
            ax.set_xlabel("interactions tried")
            ax.grid(alpha=0.3)
        axes[i][0].set_ylabel("test accuracy, " + ("discovered categories" if lab == "discovered" else "outcomes") + " (%)")
    axes[0][0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out / f"{NAME}.png", dpi=110)
    print("\n".join(lines))


def main() -> None:
    args = stream_parser(__doc__, "objects").parse_args()
    if args.candidates is not None and args.candidates < 2 * BOOTSTRAP:
        sys.exit(f"error: --candidates must be at least {2 * BOOTSTRAP} (the bootstrap, {BOOTSTRAP}, and as many to choose from)")
    write(run(args), args)


if __name__ == "__main__":
    main()
