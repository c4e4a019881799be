"""Learning speed: cluster, each feature selection and train on a table exploration, or
ReliefF and train on a traverse exploration (3900 features, given results), with peak memory,
and there a random forest on every feature: fit, model size, save, load, one row's prediction.

    python benchmarks/learn.py [--scene table|traverse|...] [--interactions 5000] [--data PATH] [--out FILE]

Explores (or reads ``--data``) an interactions set, then times each learning step the CLI
runs. Prints one JSON object and writes it to ``--out`` (default
``benchmarks/results/learn.json``, or ``learn-<scene>.json`` for another scene). Peak
memory is the process's maximum resident set size (run each scene in its own process).
"""

from __future__ import annotations

import argparse
import resource
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402

from afford.artifacts import read_artifact  # noqa: E402
from afford.datasets import interactions_from_artifact  # noqa: E402
from afford.learning import learner_settings  # noqa: E402
from afford.learn.affordances import discover_effects, rank_features, train_predictors  # noqa: E402


def timed(fn, *a, **k):
    t = time.perf_counter()
    out = fn(*a, **k)
    return out, round(time.perf_counter() - t, 2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--interactions", type=int, default=5000)
    ap.add_argument("--data", help="an interactions artefact to learn from (default: explore now)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--scene", default="table")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    results = Path(__file__).parent / "results"
    if args.out is None:
        args.out = str(results / ("learn.json" if args.scene == "table" else f"learn-{args.scene}.json"))
    if args.scene != "table":
        return given_labels(args)
    if args.data:
        data = interactions_from_artifact(read_artifact(args.data, "interactions"))
        explore_s = None
    else:
        from afford.sim.explore import explore
        from afford.sim.registry import get_scene

        data, explore_s = timed(explore, get_scene("table")(), interactions=args.interactions, seed=args.seed, workers=2)
    (effects, labels), cluster_s = timed(discover_effects, data, seed=0)
    _, cluster_pred_s = timed(discover_effects, data, prune="predictability", seed=0)
    selections = {}
    for method in ("relieff", "forward", "backward"):
        rel, selections[method] = timed(rank_features, data, labels, method=method, seed=0,
                                        group_channels=method != "relieff")
        if method == "relieff":
            chosen = {k: v.selected_ for k, v in rel.items()}
    _, train_s = timed(train_predictors, data, labels, chosen, seed=0)
    result = {
        "benchmark": "learn",
        "interactions": len(data),
        "seconds": {
            "explore_2_workers": explore_s,
            "cluster_frequency": cluster_s,
            "cluster_predictability": cluster_pred_s,
            "select_relieff": selections["relieff"],
            "select_forward_grouped": selections["forward"],
            "select_backward_grouped": selections["backward"],
            "train_rbf": train_s,
        },
    }
    result["seconds"]["pipeline_cluster_relieff_train"] = round(cluster_s + selections["relieff"] + train_s, 2)
    emit(result, args.out)


def peak_mb() -> float:
    return round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)


def given_labels(args) -> None:
    """ReliefF (Algorithm 3, m = 1000, 10 hits and misses) with its cut, then the SVMs, on given results."""
    from afford.sim.explore import explore
    from afford.sim.registry import make_scene

    if args.data:
        data, explore_s = interactions_from_artifact(read_artifact(args.data, "interactions")), None
    else:
        data, explore_s = timed(explore, make_scene(args.scene), interactions=args.interactions, seed=args.seed,
                                workers=2)
    before = peak_mb()
    labels = data.result.astype(int)
    kernel, folds = learner_settings(None, data)  # the scene's, as select-features and train take it
    relevance, relieff_s = timed(rank_features, data, labels, method="relieff", seed=0, kernel=kernel)
    chosen = {k: v.selected_ for k, v in relevance.items()}
    after_relieff = peak_mb()
    _, train_s = timed(train_predictors, data, labels, chosen, kernel=kernel, folds=folds, seed=0)
    forest = forest_figures(data, labels, chosen)
    result = {
        "benchmark": "learn",
        "scene": args.scene,
        "interactions": len(data),
        "features": len(data.schema),
        "selected": {k: int(len(v)) for k, v in chosen.items()},
        "kernel": kernel,
        "folds": folds,
        "seconds": {"explore_2_workers": explore_s, "select_relieff": relieff_s, "train": train_s,
                    "pipeline_relieff_train": round(relieff_s + train_s, 2)},
        "peak_memory_mb": {"after_loading": before, "after_relieff": after_relieff, "after_train": peak_mb()},
        "forest": forest,
    }
    emit(result, args.out)


def forest_figures(data, labels, chosen) -> dict:
    """``train --kernel forest`` on every feature: the fit, one model file's bytes, saving and
    loading them (skops, the trees packed), and one row's prediction (navigation's call)."""
    import numpy as np
    import skops.io as sio

    from afford.artifacts import dump_estimator
    from afford.learn.predictors import TRUSTED_TYPES

    everything = {k: np.arange(len(data.schema)) for k in chosen}
    models, fit_s = timed(train_predictors, data, labels, everything, kernel="forest", seed=0)
    blobs, dump_s = timed(lambda: [dump_estimator(m) for m in models.values()])
    _, load_s = timed(lambda: [sio.loads(b, trusted=TRUSTED_TYPES) for b in blobs])
    model = next(iter(models.values()))
    row = data.before_rows(np.arange(1))[:, :model.n_features_in_]  # the traverse moves take no parameters
    model.predict_proba(row)
    _, one_row_s = timed(lambda: [model.predict_proba(row) for _ in range(100)])
    return {"train_s": fit_s, "model_mb": round(sum(map(len, blobs)) / 2**20, 1), "save_s": dump_s, "load_s": load_s,
            "predict_one_row_ms": round(one_row_s * 10, 2)}


if __name__ == "__main__":
    main()
