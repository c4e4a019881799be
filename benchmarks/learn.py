"""Learning speed on a table-scene exploration: cluster, each feature selection, train.

    python benchmarks/learn.py [--interactions 5000] [--data PATH] [--out benchmarks/results/learn.json]

Explores (or reads ``--data``) an interactions set, then times each learning step the CLI
runs. Prints one JSON object and writes it to ``--out``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402

from afford_cli.artifacts import read_artifact  # noqa: E402
from afford_cli.datasets import interactions_from_artifact  # noqa: E402
from learn.affordances import discover_effects, rank_features, train_predictors  # noqa: E402


def timed(fn, *a, **k):
    t = time.perf_counter()
    out = fn(*a, **k)
    return out, round(time.perf_counter() - t, 2)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--interactions", type=int, default=5000)
    ap.add_argument("--data", help="an interactions artefact to learn from (default: explore now)")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "learn.json"))
    args = ap.parse_args()
    if args.data:
        data = interactions_from_artifact(read_artifact(args.data, "interactions"))
        explore_s = None
    else:
        from sim.explore import explore
        from sim.registry import get_scene

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


if __name__ == "__main__":
    main()
