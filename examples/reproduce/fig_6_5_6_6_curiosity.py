"""Thesis figures 6.5 and 6.6: curiosity-driven learning of go-forward, against random exploration.

    python examples/reproduce/fig_6_5_6_6_curiosity.py [--quick] [--seed S] [--out DIR] [--workers K]

The thesis (chapter 6) learned go-forward's traversability from 3000 candidate situations
with a bootstrap of random interactions and then a curiosity band of width tau around the
SVM's boundary, testing on 2000 situations of another room. It found that a bootstrap of
25 suffices (10 stays below 90 %; more gains nothing, figure 6.5) and that tau = 0.5 is
best (figure 6.6), each box over 10 orderings of the candidates at the 100th, 250th and
400th interaction.

Here the candidates are places in one room of the `traverse-room` scene (room S, the
seed; 60 objects of 10-30 cm in a walled 6 x 6 m room) seen with chapter 6's perception
(a 30 x 30 grid in one layer, 35 100 features), scanned once; every candidate's
go-forward result is run once in PhysX up front (the robot's own reading), so the
orderings can replay the stream without running the physics again: a strategy only ever
learns the results of the candidates it tries. The test set is another room's (S + 1). Beyond the thesis, the same stream and test set compare every strategy of
`afford explore --strategy` by the interactions each needs to reach 95 % of the accuracy
that all candidates give (the batch learner on all of them: ReliefF's 250 features and a
linear SVM), medians and quartiles over the orderings.

Both rooms are harder than ``traverse-room``'s own (30 objects of 20-40 cm): 60 loose
objects of 10-30 cm by default (``--clutter``, ``--size-min``, ``--size-max``; give 30,
0.2 and 0.4 for the scene's own room, where go-forward is learned almost entirely from
the bootstrap). The "strategies" rows also give, as ``online``, the interactions needed
against a second reference: the online learner given every candidate (random's end in
the same ordering). The figure is box plots over the orderings (``values`` in the rows).

Full mode: 3000 candidates, 2000 test situations, 10 orderings (about an hour here);
``--quick``: 450 candidates, 200 test situations, 3 orderings (a few minutes).

Writes ``DIR/fig_6_5_6_6_curiosity.{md,json,png}``; the JSON's ``rows`` hold one row per
figure, setting and checkpoint: ``figure`` ("6.5", "6.6" or "strategies"), ``bootstrap``,
``tau``, ``strategy``, ``interactions`` (the checkpoint), ``median``, ``q1``, ``q3`` (test
accuracy over the orderings; for "strategies", the interactions needed), ``values`` (one
per ordering; None where it never got there), and ``thesis`` where the thesis states a
finding. The PNG draws them as box plots: figures 6.5 and 6.6, and the strategies'
interactions needed (an ordering that never got there drawn at every candidate).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, quartiles, stream_parser  # noqa: E402

NAME = "fig_6_5_6_6_curiosity"
CHECKPOINTS = (100, 250, 400)
BOOTSTRAPS = (10, 25, 50, 100)
TAUS = (0.05, 0.1, 0.5, 1.0)
#: What the thesis says of the two figures (6.5.1, 6.5.2), quoted from its text.
THESIS = {
    "6.5": "a bootstrap of 10 stays below 90 %; more than 25 does not further increase the performance",
    "6.6": "tau too small keeps the robot from interesting situations, too large slows learning; tau = 0.5 chosen",
}


def _labels(scene, seed: int, candidates: list[int], b: int) -> list[tuple[int, int]]:
    from afford.sim.explore import try_candidate

    return [(c, try_candidate(scene, seed, c, b)[0]) for c in candidates]


def stream(scene, n: int, seed: int, workers: int) -> tuple[np.ndarray, np.ndarray]:
    """n candidates scanned, and go-forward's result in each (run once, in PhysX)."""
    from joblib import Parallel, delayed

    from afford.sim.explore import scan_candidates

    X = scan_candidates(scene, n, seed=seed, workers=workers)
    b = [x.name for x in scene.behaviors].index("go-forward")
    chunks = [list(range(a, min(a + 25, n))) for a in range(0, n, 25)]
    y = np.zeros(n, dtype=int)
    for part in Parallel(n_jobs=workers)(delayed(_labels)(scene, seed, c, b) for c in chunks):
        for c, r in part:
            y[c] = r
    return X, y


def batch_accuracy(X, y, Xt, yt, seed: int, n_features: int = 250) -> float:
    """What every candidate teaches: ReliefF on all of them keeps the 250 most relevant
    features and a linear SVM learns from all (the batch learner, chapter 5's way)."""
    from sklearn.svm import LinearSVC

    from afford.learn.relevance import relieff

    lo = X.min(axis=0)
    span = np.where(X.max(axis=0) > lo, X.max(axis=0) - lo, 1.0)
    Z, Zt = (X - lo) / span, (Xt - lo) / span
    cols = np.argsort(-relieff(Z, y, random_state=seed), kind="stable")[:n_features]
    svm = LinearSVC(C=1.0, dual="auto", max_iter=5000, random_state=seed).fit(Z[:, cols], y)
    return float(np.mean(svm.predict(Zt[:, cols]) == yt))


def at(curve: list[dict], k: int) -> float:
    """Test accuracy once ``k`` interactions were tried (the last point at or before k)."""
    points = [c for c in curve if c["interactions"] <= k]
    return points[-1]["accuracy"] if points else curve[0]["accuracy"]


def needed(curve: list[dict], target: float) -> float:
    return next((float(c["interactions"]) for c in curve if c["accuracy"] >= target), float("nan"))


def run(args) -> dict:
    from joblib import Parallel, delayed

    from afford.learn.online import learn_online
    from afford.sim.registry import make_scene

    n, t, orderings = (450, 200, 3) if args.quick else (3000, 2000, 10)
    n, t, orderings = args.candidates or n, args.test_size or t, args.orderings or orderings
    room = {"grid": 30, "layers": 1, "clutter": args.clutter, "size_min": args.size_min, "size_max": args.size_max}
    X, y = stream(make_scene("traverse-room", room=args.seed, **room), n, args.seed, args.workers)
    Xt, yt = stream(make_scene("traverse-room", room=args.seed + 1, **room), t, args.seed + 1, args.workers)
    perms = [np.random.default_rng(args.seed * 100 + o).permutation(n) for o in range(orderings)]

    def curve(strategy: str, bootstrap: int, tau: float, o: int) -> list[dict]:
        p = perms[o]
        return learn_online(X[p], y[p], strategy, bootstrap=bootstrap, tau=tau, X_test=Xt, y_test=yt, every=5,
                            seed=o).curve

    settings = ([("6.5", "margin", b, 0.5) for b in BOOTSTRAPS]
                + [("6.6", "margin", 50, tau) for tau in TAUS] + [("6.6", "random", 50, None)]
                + [("strategies", s, 25, 0.5) for s in ("random", "margin", "entropy", "committee")])
    jobs = [(s, o) for s in settings for o in range(orderings)]
    curves = Parallel(n_jobs=args.workers)(delayed(curve)(s[1], s[2], s[3] or 0.5, o) for s, o in jobs)
    by = {}
    for (s, o), c in zip(jobs, curves):
        by.setdefault(s, []).append(c)
    # the same learner given every candidate: random's end, ordering by ordering
    ends = [c[-1]["accuracy"] for c in by[("strategies", "random", 25, 0.5)]]

    everything = batch_accuracy(X, y, Xt, yt, args.seed)
    rows = []
    for (figure, strategy, bootstrap, tau), cs in by.items():
        base = {"figure": figure, "strategy": strategy, "bootstrap": bootstrap, "tau": tau}
        if figure == "strategies":
            values = [needed(c, 0.95 * everything) for c in cs]
            rows.append({**base, "interactions": None, **quartiles(values),
                         "values": [v if np.isfinite(v) else None for v in values],  # None: never reached
                         "online": quartiles([needed(c, 0.95 * end) for c, end in zip(cs, ends)]),
                         "tried": quartiles([c[-1]["interactions"] for c in cs]), "thesis": None})
            continue
        for k in CHECKPOINTS:
            values = [at(c, k) for c in cs]
            rows.append({**base, "interactions": k, **quartiles(values), "values": values, "thesis": THESIS[figure]})
    return {"rows": rows, "all_candidates_accuracy": round(float(everything), 4), "candidates": n, "test": t,
            "room": {k: v for k, v in room.items() if k in ("clutter", "size_min", "size_max") and v is not None},
            "orderings": orderings, "go_forward_traversable": round(float(np.mean(y)), 4), "n_features": X.shape[1]}


def write(doc: dict, args) -> None:
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, **doc}
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    rows = doc["rows"]
    pct = lambda r: "-" if r["median"] is None else f"{100 * r['median']:.1f} % ({100 * r['q1']:.1f}-{100 * r['q3']:.1f})"
    lines = ["# Curiosity-driven learning of go-forward (thesis figures 6.5 and 6.6)", "",
             f"Seed {args.seed}, commit {doc['commit']}, {'quick' if args.quick else 'full'} mode: "
             f"{doc['candidates']} places in room {args.seed}, {doc['test']} test places in room {args.seed + 1}, {doc['orderings']} orderings, "
             f"{doc['n_features']} features; go-forward traversable in {100 * doc['go_forward_traversable']:.0f} % of "
             f"the candidates; all candidates give {100 * doc['all_candidates_accuracy']:.1f} %"
             + (f"; a harder room: {', '.join(f'{k} {v}' for k, v in doc['room'].items())}" if doc["room"] else "")
             + ".", "",
             "Median test accuracy (quartiles) over the orderings at the 100th, 250th and 400th interaction.", "",
             "## Figure 6.5: the bootstrap (tau = 0.5)", "", f"Thesis: {THESIS['6.5']}.", "",
             "| bootstrap | " + " | ".join(f"{k}" for k in CHECKPOINTS) + " |", "|---|" + "---|" * len(CHECKPOINTS)]
    for b in BOOTSTRAPS:
        cells = [r for r in rows if r["figure"] == "6.5" and r["bootstrap"] == b]
        lines.append(f"| {b} | " + " | ".join(pct(r) for r in cells) + " |")
    lines += ["", "## Figure 6.6: the curiosity threshold (bootstrap 50)", "", f"Thesis: {THESIS['6.6']}.", "",
              "| tau | " + " | ".join(f"{k}" for k in CHECKPOINTS) + " |", "|---|" + "---|" * len(CHECKPOINTS)]
    for tau in list(TAUS) + [None]:
        cells = [r for r in rows if r["figure"] == "6.6" and r["tau"] == tau]
        lines.append(f"| {'no curiosity' if tau is None else tau} | " + " | ".join(pct(r) for r in cells) + " |")
    lines += ["", "## Beyond the thesis: interactions to reach 95 % of the all-candidates accuracy (bootstrap 25)", "",
              "Two references: the batch learner on all candidates (ReliefF on all of them), and the online "
              "learner given every candidate (random's end in the same ordering, features from the bootstrap).", "",
              "| strategy | interactions, batch reference (median, quartiles) | online reference | "
              "candidates tried in all (median) |", "|---|---|---|---|"]
    need = lambda q: "never" if q["median"] is None else f"{q['median']:.0f} ({q['q1']:.0f}-{q['q3']:.0f})"
    for r in (r for r in rows if r["figure"] == "strategies"):
        lines.append(f"| {r['strategy']} | {need(r)} | {need(r['online'])} | {r['tried']['median']:.0f} |")
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 3.8), gridspec_kw={"width_ratios": [4, 5, 3]})
    axes[1].sharey(axes[0])
    for ax, figure, key, values in ((axes[0], "6.5", "bootstrap", BOOTSTRAPS), (axes[1], "6.6", "tau", list(TAUS) + [None])):
        for i, v in enumerate(values):
            cells = [r for r in rows if r["figure"] == figure and r[key] == v and r["median"] is not None]
            ax.boxplot([[100 * a for a in r["values"]] for r in cells], positions=[i * 4 + j for j in range(len(cells))],
                       widths=0.7, patch_artist=True, boxprops={"facecolor": "#c6dbef"}, medianprops={"color": "#08519c"})
        ax.set_xticks([i * 4 + 1 for i in range(len(values))],
                      [("none" if v is None else str(v)) for v in values])
        ax.set_xlabel(f"{key} (boxes: 100th, 250th, 400th interaction)")
        ax.set_title(f"figure {figure}")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("test accuracy over the orderings (%)")
    strategies = [r for r in rows if r["figure"] == "strategies"]
    # an ordering that never reaches the target is drawn at every candidate (the most it could need)
    axes[2].boxplot([[doc["candidates"] if v is None else v for v in r["values"]] for r in strategies],
                    widths=0.6, patch_artist=True, boxprops={"facecolor": "#fdd0a2"}, medianprops={"color": "#a63603"})
    axes[2].set_xticks(range(1, len(strategies) + 1), [r["strategy"] for r in strategies])
    axes[2].set_ylabel("interactions to 95 % of all candidates' accuracy")
    axes[2].set_title("strategies (bootstrap 25)")
    axes[2].grid(alpha=0.3)
    fig.tight_layout()
    fig.savefig(out / f"{NAME}.png", dpi=110)
    print("\n".join(lines))


def main() -> None:
    ap = stream_parser(__doc__, "situations")
    ap.add_argument("--clutter", type=int, default=60, help="loose objects in each room (60; traverse-room's own is 30)")
    ap.add_argument("--size-min", type=float, default=0.1, help="smallest loose-object dimension, metres (0.1; its own 0.2)")
    ap.add_argument("--size-max", type=float, default=0.3, help="largest loose-object dimension, metres (0.3; its own 0.4)")
    args = ap.parse_args()
    if args.candidates is not None and args.candidates < 110:
        sys.exit("error: --candidates must be at least 110 (the largest bootstrap, 100, and some to choose from)")
    write(run(args), args)


if __name__ == "__main__":
    main()
