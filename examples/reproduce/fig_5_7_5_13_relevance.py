"""Thesis Figures 5.7 and 5.13 (5.6.3): where the robot looks, and how few features it needs.

    python examples/reproduce/fig_5_7_5_13_relevance.py [--quick] [--seed S] [--out DIR] [--workers W]
        [--data TRAIN] [--test TEST]

On ``traverse`` (5.6.1) ReliefF ranks the 3900 grid features per move and cuts the ranking
as ``afford select-features`` does (``learn.affordances.rank_features``, chapter 5's linear
SVM scoring the cut). Then:

* **Figure 5.7, relevance maps.** Per move, each grid cell's relevance, the sum of the
  positive ReliefF weights of its kept features, spread over the cell's pixels in all four
  overlapping layers and drawn over one range view of the scene (darker: more relevant).
  ``centre_of_relevance`` is the map's weighted mean column, -1 (left edge) to 1 (right).
* **Figure 5.13, perceptual economy.** For go-forward: held-out accuracy of the linear SVM
  (C by 5-fold cross-validation, as ``afford train``) on the n most relevant features, n =
  1, 2, 4, ... and all, by ReliefF's ranking; and by forward selection (the thesis's
  *sequentialfs*), greedily adding the feature whose 3-fold cross-validated accuracy is
  best, for n up to 20. Forward selection over 3900 candidates, 20 times, is 234 000 fits:
  here its candidates are ReliefF's 200 best (``--quick``: 60), which we say openly. As the
  thesis's bars, the test set is split into 10 parts and the best, median and worst
  accuracy over them are given.
* **Feature categories (5.6.3.2).** The shares of distance (min, max, mean range), theta
  (the normals' polar angle: vertical shape) and phi (their heading: horizontal shape)
  among go-forward's 20 most relevant features, and over all moves.

Full mode: 5000 training interactions (seed S) and 2100 test interactions (300 environments,
seed S + 1) unless ``--data``/``--test`` give explored files of ``traverse``; ``--quick``: 100
and 20 environments (``--episodes``, ``--test-episodes`` set them; ``make reproduce``'s
``--cache`` shares them with the furniture and accuracy scripts, which explore the same).

Writes ``DIR/fig_5_7_5_13_relevance.{md,json,png}``; the JSON has ``maps`` (per move: the
cell relevances, ``centre_of_relevance``, ``kept``), ``economy`` (rows ``method``, ``n``,
``best``, ``median``, ``worst``, ``accuracy`` on the whole test set, ``thesis``) and
``categories``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import commit, explored, parser  # noqa: E402

NAME = "fig_5_7_5_13_relevance"
SCENE = "traverse"
BEHAVIOR = "go-forward"
#: Figure 5.13 as the thesis's text reads it off (5.7.2): accuracy with the n most relevant features.
THESIS_ECONOMY = {"relieff": {1: 0.64, 4: 0.78, 20: 0.82, 320: 0.87}, "forward": {1: 0.72, 4: 0.80}}
#: 5.6.3.2: shares among the 20 most relevant features (the thesis's "lateral shape" taken as
#: theta, since it finds the vertical shape the more important; an assumption).
THESIS_CATEGORIES = {"distance": 0.65, "theta": 0.30, "phi": 0.05}
PARTS = 10


def load_or_explore(path: str | None, episodes: int, seed: int, args):
    import afford

    if path is not None:
        data = afford.load_interactions(path)
        if data.result is None or "go-forward" not in data.behavior_names:
            sys.exit(f"error: {path} holds no traverse interactions with the robot's results")
        return data
    return explored(SCENE, args, seed=seed, episodes=episodes)


def relevance_maps(relevance: dict, spec) -> dict:
    """Per move: (layers, cells, cells) cell relevance, normalised to a maximum of 1."""
    from afford.features.grid import feature_cells

    cells = feature_cells(spec)
    out = {}
    for name, fr in relevance.items():
        m = np.zeros((spec.layers, spec.cells, spec.cells))
        for f in np.asarray(fr.selected_, dtype=int):
            m[tuple(cells[f])] += max(float(fr.scores_[f]), 0.0)
        out[name] = m / m.max() if m.max() > 0 else m
    return out


def pixel_map(cell_map: np.ndarray, spec, shape: tuple[int, int]) -> np.ndarray:
    """Cell relevance spread over the pixels of every layer's cells (summed over layers)."""
    from afford.features.grid import cell_edges

    R, C = cell_edges(spec, shape)
    img = np.zeros(shape)
    for (layer, r, c), v in np.ndenumerate(cell_map):
        img[R[layer, r]:R[layer, r + 1], C[layer, c]:C[layer, c + 1]] += v
    return img / img.max() if img.max() > 0 else img


def centre_of_relevance(img: np.ndarray) -> float:
    w = img.sum(axis=0)
    x = np.linspace(-1.0, 1.0, img.shape[1])
    return round(float((w * x).sum() / w.sum()), 4) if w.sum() > 0 else 0.0


def forward_selection(X: np.ndarray, y: np.ndarray, pool: np.ndarray, n: int, seed: int) -> list[int]:
    """Greedy forward selection over ``pool``: each step adds the feature whose 3-fold
    cross-validated accuracy of a linear SVM on the features so far is best."""
    from sklearn.model_selection import StratifiedKFold, cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import MinMaxScaler
    from sklearn.svm import LinearSVC

    folds = StratifiedKFold(3, shuffle=True, random_state=seed)
    chosen: list[int] = []
    for _ in range(min(n, pool.size)):
        best, best_score = None, -1.0
        for f in pool:
            if f in chosen:
                continue
            model = make_pipeline(MinMaxScaler(), LinearSVC(C=1.0, dual=False))
            s = float(cross_val_score(model, X[:, chosen + [int(f)]], y, cv=folds).mean())
            if s > best_score + 1e-12:
                best, best_score = int(f), s
        chosen.append(best)
    return chosen


def economy(train, test, ranking: np.ndarray, args) -> list[dict]:
    from afford.learn.predictors import AffordancePredictor

    b = train.behavior_names.index(BEHAVIOR)
    tr, te = np.flatnonzero(train.behavior == b), np.flatnonzero(test.behavior == b)
    X, y = train.before_rows(tr), train.result[tr].astype(int)
    Xt, yt = test.before_rows(te), test.result[te].astype(int)
    parts = np.array_split(np.random.default_rng(args.seed).permutation(yt.size), PARTS)
    d = X.shape[1]
    sizes = sorted({*(2 ** k for k in range(int(np.log2(d)) + 1)), d})
    pool = ranking[: 60 if args.quick else 200]
    forward = forward_selection(X, y, pool, 8 if args.quick else 20, args.seed)
    f_sizes = [n for n in (1, 2, 4, 8, 16, 20) if n <= len(forward)]
    rows = []
    for method, order, ns in (("relieff", ranking, sizes), ("forward", np.asarray(forward), f_sizes)):
        for n in ns:
            keep = order[:n]
            model = AffordancePredictor(kernel="linear", cv=5, random_state=args.seed).fit(X[:, keep], y)
            right = model.predict(Xt[:, keep]) == yt
            acc = [float(right[p].mean()) for p in parts]
            rows.append({"method": method, "n": int(n), "best": round(max(acc), 4), "median": round(float(np.median(acc)), 4),
                         "worst": round(min(acc), 4), "accuracy": round(float(right.mean()), 4),
                         "thesis": THESIS_ECONOMY[method].get(int(n))})
    return rows


def categories(relevance: dict, schema) -> dict:
    names = schema.names

    def shares(idx) -> dict:
        kinds = ["distance" if names[i].rsplit("_", 1)[-1] in ("min", "max", "mean") else names[i].split("_")[-2]
                 for i in idx]
        return {k: round(kinds.count(k) / len(kinds), 4) for k in ("distance", "theta", "phi")}

    top = {name: np.argsort(-fr.scores_, kind="stable")[:20] for name, fr in relevance.items()}
    return {"go-forward": shares(top[BEHAVIOR]), "all_moves": shares(np.concatenate(list(top.values()))),
            "thesis": THESIS_CATEGORIES}


def main() -> None:
    ap = parser(__doc__)
    ap.add_argument("--data", default=None, help="explored traverse interactions to learn from (default: explore)")
    ap.add_argument("--test", default=None, help="explored traverse interactions to test on (default: explore)")
    ap.add_argument("--episodes", type=int, default=None, help="training environments to explore (default 715; quick 100)")
    ap.add_argument("--test-episodes", type=int, default=None, help="test environments to explore (default 300; quick 20)")
    args = ap.parse_args()
    for flag, v in (("--episodes", args.episodes), ("--test-episodes", args.test_episodes)):
        if v is not None and v < PARTS:
            sys.exit(f"error: {flag} must be at least {PARTS}, got {v}")
    for p in (args.data, args.test):
        if p is not None and not Path(p).is_file():
            sys.exit(f"error: no file {p}")
    import afford
    from afford.errors import AffordError
    from afford.features.errors import DataError
    from afford.learn.affordances import rank_features

    try:
        train = load_or_explore(args.data, args.episodes or (100 if args.quick else 715), args.seed, args)
        test = load_or_explore(args.test, args.test_episodes or (20 if args.quick else 300), args.seed + 1, args)
        scene = afford.make_scene(SCENE)
        relevance = rank_features(train, train.result.astype(int), kernel="linear", seed=args.seed)
        spec = scene.config.grid
        cell_maps = relevance_maps(relevance, spec)
        rows = economy(train, test, np.asarray(relevance[BEHAVIOR].ranking_, dtype=int), args)
        world = scene.build(scene.sample(np.random.default_rng(args.seed)), np.random.default_rng(args.seed))
        world.perceive()
        view = np.asarray(world.last_image.ranges, dtype=float)
    except (AffordError, DataError) as exc:
        sys.exit(f"error: {exc}")
    pixel = {b: pixel_map(m, spec, view.shape) for b, m in cell_maps.items()}
    doc = {"name": NAME, "seed": args.seed, "commit": commit(), "quick": args.quick, "scene": SCENE,
           "train_interactions": len(train), "test_interactions": len(test),
           "maps": {b: {"cells": np.round(m, 4).tolist(), "centre_of_relevance": centre_of_relevance(pixel[b]),
                        "kept": int(len(relevance[b].selected_))} for b, m in cell_maps.items()},
           "economy": rows, "categories": categories(relevance, train.schema)}
    write(doc, Path(args.out), pixel, view)
    print((Path(args.out) / f"{NAME}.md").read_text())


def write(doc: dict, out: Path, pixel: dict, view: np.ndarray) -> None:
    out.mkdir(parents=True, exist_ok=True)
    (out / f"{NAME}.json").write_text(json.dumps(doc, indent=1) + "\n")
    pct = lambda v: "-" if v is None else f"{100 * v:.0f} %"  # noqa: E731
    lines = ["# Figures 5.7 and 5.13: relevance maps and perceptual economy (thesis 5.6.3)", "",
             f"Scene `{SCENE}`, seed {doc['seed']}, commit {doc['commit']}, {'quick' if doc['quick'] else 'full'} mode: "
             f"{doc['train_interactions']} training and {doc['test_interactions']} test interactions.", "",
             "## Where each move looks (Figure 5.7)", "",
             "| move | features kept (of 3900) | centre of relevance (-1 left, +1 right) |", "|---|---|---|"]
    lines += [f"| {b} | {m['kept']} | {m['centre_of_relevance']:+.2f} |" for b, m in doc["maps"].items()]
    lines += ["", "## Accuracy with the n most relevant features, go-forward (Figure 5.13)", "",
              "| method | n | whole test set | best / median / worst of 10 parts | thesis |", "|---|---|---|---|---|"]
    lines += [f"| {r['method']} | {r['n']} | {pct(r['accuracy'])} | {pct(r['best'])} / {pct(r['median'])} / {pct(r['worst'])} "
              f"| {pct(r['thesis'])} |" for r in doc["economy"]]
    c = doc["categories"]
    lines += ["", "## Kinds of feature among the 20 most relevant (5.6.3.2)", "",
              "| | distance | theta (vertical shape) | phi (horizontal shape) |", "|---|---|---|---|"]
    lines += [f"| {k} | {pct(v['distance'])} | {pct(v['theta'])} | {pct(v['phi'])} |"
              for k, v in (("go-forward", c["go-forward"]), ("all moves", c["all_moves"]), ("thesis", c["thesis"]))]
    lines += ["", "Forward selection chooses among ReliefF's best candidates only (see the script's docstring); "
              "the thesis's shape categories are mapped to theta and phi by our reading of its text."]
    (out / f"{NAME}.md").write_text("\n".join(lines) + "\n")
    _figure(doc, pixel, view, out / f"{NAME}.png")


def _figure(doc: dict, pixel: dict, view: np.ndarray, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    moves = list(pixel)
    fig = plt.figure(figsize=(13, 6.5))
    grid = fig.add_gridspec(2, 5)
    shown = np.where(np.isfinite(view), view, np.nan)
    for i, b in enumerate(moves):
        ax = fig.add_subplot(grid[i // 4, i % 4])
        ax.imshow(shown, cmap="gray", interpolation="nearest")
        ax.imshow(pixel[b], cmap="Reds", alpha=np.clip(0.85 * pixel[b], 0.0, 1.0), vmin=0, vmax=1, interpolation="nearest")
        ax.set_title(f"{b} ({doc['maps'][b]['kept']} kept)", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    ax = fig.add_subplot(grid[:, 4])
    for method, style in (("relieff", "o-"), ("forward", "s-")):
        r = [x for x in doc["economy"] if x["method"] == method]
        n = [x["n"] for x in r]
        ax.errorbar(n, [x["median"] for x in r], yerr=[[x["median"] - x["worst"] for x in r], [x["best"] - x["median"] for x in r]],
                    fmt=style, capsize=3, label=f"{method} (ours)")
        t = THESIS_ECONOMY[method]
        ax.plot(list(t), list(t.values()), "x--", label=f"{method} (thesis)")
    ax.set_xscale("log", base=2)
    ax.set_xlabel("features kept")
    ax.set_ylabel("go-forward accuracy")
    ax.set_ylim(0.4, 1.0)
    ax.legend(fontsize=7)
    ax.set_title("Figure 5.13", fontsize=9)
    fig.suptitle("Figure 5.7: relevant grid cells per move over one range view (left of the image: the robot's left)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    main()
