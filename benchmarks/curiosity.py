"""Curiosity's costs (issue 12): is deciding whether a situation is interesting cheap beside acting in it?

    python benchmarks/curiosity.py [--candidates N] [--out benchmarks/results/curiosity.json]

With chapter 6's perception (the `traverse` scene, a 30 x 30 grid in one layer: 35 100
features) this times, per candidate: the scan (ray casting, no physics), the grid
features of the scan, and the margin decision on a fitted online SVM (the 250 chosen
features, scaled, one decision value); per tried candidate: one go-forward in PhysX
(world build and the move) and the SVM's refit on 100, 500 and 1000 tried rows. It also
reports the memory 3000 candidates' features take (float32) and this process's peak.

At the table (curiosity over discovered effect categories), per candidate: building its
world, the look (ray casting, segmentation and the object's features), and the entropy
decision (the RBF SVM over the categories found in a bootstrap, its calibrated
probabilities and their entropy); per tried candidate, one push-forward in PhysX.
"""

from __future__ import annotations

import argparse
import platform
import resource
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--candidates", type=int, default=60, help="candidates scanned and tried for the timings")
    ap.add_argument("--out", default=str(Path(__file__).parent / "results" / "curiosity.json"))
    args = ap.parse_args()

    from afford.features.grid import grid_features
    from afford.learn.online import learn_online
    from afford.sim.explore import episode_rng, try_candidate
    from afford.sim.registry import make_scene

    scene = make_scene("traverse", grid=30, layers=1)
    spec = scene.config.grid
    scans, features, X, y, physics = [], [], [], [], []
    b = [x.name for x in scene.behaviors].index("go-forward")
    for c in range(args.candidates):
        rng = episode_rng(7, c)
        world = scene.build(scene.sample(rng), rng).world
        t = time.perf_counter()
        image = world.scan()
        scans.append(time.perf_counter() - t)
        t = time.perf_counter()
        X.append(grid_features(image, spec))
        features.append(time.perf_counter() - t)
        t = time.perf_counter()
        y.append(try_candidate(scene, 7, c, b)[0])
        physics.append(time.perf_counter() - t)
    X, y = np.stack(X), np.array(y)
    run = learn_online(X, y, "random", bootstrap=min(25, len(y)), seed=0)  # a fitted learner, features chosen
    from afford.learn.online import _Learner

    cols = run.selected
    lo, span = X[:, cols].min(0), np.ptp(X[:, cols], 0) + 1e-6
    learner = _Learner(cols, lo, span, 1.0, 0)
    Z = learner.inputs(X)
    learner.fit(Z, y if np.unique(y).size > 1 else np.r_[y[:-1], 1 - y[-1]])
    decide = []
    for x in X:
        t = time.perf_counter()
        abs(float(learner.decision(learner.inputs(x[None, :]))[0])) < 0.5
        decide.append(time.perf_counter() - t)
    refit = {}
    rng = np.random.default_rng(0)
    for n in (100, 500, 1000):
        Zn = rng.uniform(0, 1, (n, len(cols)))
        yn = (Zn[:, 0] + 0.3 * rng.standard_normal(n) > 0.5).astype(int)
        t = time.perf_counter()
        learner.fit(Zn, yn)
        refit[str(n)] = round(1000 * (time.perf_counter() - t), 2)
    ms = lambda v: round(1000 * float(np.median(v)), 2)
    table = _table(args.candidates, ms)
    result = {
        "benchmark": "curiosity",
        "machine": {"python": platform.python_version(), "cpus": __import__("os").cpu_count(),
                    "platform": platform.platform()},
        "n_features": int(X.shape[1]), "candidates_timed": args.candidates,
        "per_candidate_ms": {"scan": ms(scans), "grid_features": ms(features), "margin_decision": ms(decide),
                             "deciding_with_features": round(ms(features) + ms(decide), 2)},
        "per_try_ms": {"physics_go_forward": ms(physics)},
        "refit_ms_by_rows_tried": refit,
        "table": table,
        "memory": {"features_of_3000_candidates_mb": round(3000 * X.shape[1] * 4 / 2**20, 1),
                   "peak_rss_mb": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024, 1)},
    }
    emit(result, args.out)


def _table(n: int, ms) -> dict:
    """The table's costs (see the module docstring)."""
    from afford.curiosity import categoriser
    from afford.learn.online import _Learner, _as_columns, _normalised_entropy, _out_of_fold_calibrator
    from afford.learning import clustering_settings
    from afford.sim.explore import episode_rng, try_candidate_effect
    from afford.sim.registry import make_scene

    scene = make_scene("table")
    build, look, physics, X, E = [], [], [], [], []
    for c in range(max(n, 40)):
        rng = episode_rng(7, c)
        layout = scene.sample(rng)
        t = time.perf_counter()
        world = scene.build(layout, rng)
        build.append(time.perf_counter() - t)
        t = time.perf_counter()
        seen = world.perceive()
        look.append(time.perf_counter() - t)
        t = time.perf_counter()
        row = try_candidate_effect(scene, 7, c, 0)
        physics.append(time.perf_counter() - t)
        if len(row):
            X.append(seen[0])
            E.append(row.effects_of(np.zeros(1, dtype=int))[0])
    X, E = np.asarray(X, dtype=float), np.asarray(E)
    clustering = clustering_settings(scene.describe(), scene.schema, "the table scene")
    categorise, found = categoriser(scene, clustering, 0, 0, X)
    y = np.asarray(categorise(list(E), list(range(len(E))))(list(E)))
    cols = np.arange(X.shape[1])
    lo, span = X.min(0), np.ptp(X, 0) + 1e-6
    learner = _Learner(cols, lo, span, 10.0, 0, "rbf")
    Z = learner.inputs(X)
    learner.fit(Z, y)
    import warnings

    from sklearn.exceptions import ConvergenceWarning

    with warnings.catch_warnings():  # as learn_online runs it (lbfgs stops at its cap on near-separable outputs)
        warnings.simplefilter("ignore", ConvergenceWarning)
        calibrator = _out_of_fold_calibrator(Z, y, "rbf", 10.0, 0)
    decide = []
    for x in X:
        t = time.perf_counter()
        d = learner.decision(learner.inputs(x[None, :]))
        _normalised_entropy(calibrator.predict_proba(_as_columns(d))[0]) if calibrator is not None else 1.0
        decide.append(time.perf_counter() - t)
    return {"candidates_timed": len(build), "n_features": int(X.shape[1]),
            "n_categories": int(found["categories"].n_categories_), "calibrated": calibrator is not None,
            "per_candidate_ms": {"build_world": ms(build), "look_and_features": ms(look),
                                 "entropy_decision": ms(decide), "deciding_with_features": round(ms(look) + ms(decide), 2)},
            "per_try_ms": {"physics_push_forward_with_build": ms(physics)}}


if __name__ == "__main__":
    main()
