"""Held-out accuracy against training rows per behaviour, with the categories held fixed.

    python benchmarks/learning_curve.py --model M --data BIG --test TEST [--sizes 1200,2400,4800]

Takes a model's effect categories and selected features as they are, labels the rows of a
(large) interactions file and of a test file with those categories, and trains the same
calibrated SVM (``learn.predictors.AffordancePredictor``) on the first N rows of each
behaviour for every N in ``--sizes``; prints one JSON object with the test accuracy per
behaviour and size. It separates what more data buys from what finer categories cost
(clustering more data afresh finds more categories). Not part of ``make bench``: the data
it needs take minutes to explore, e.g.
``afford explore --interactions 20000 --seed 11 --workers 2 -o big.afford``.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, help="a model artefact (its categories and features are kept)")
    ap.add_argument("--data", required=True, help="an interactions artefact to train on")
    ap.add_argument("--test", required=True, help="an interactions artefact to test on")
    ap.add_argument("--sizes", default="1200,2400,4800", help="training rows per behaviour, comma-separated")
    ap.add_argument("--out", default="benchmarks/results/learning_curve.json")
    args = ap.parse_args()

    from afford.artifacts import read_artifact
    from afford.datasets import interactions_from_artifact
    from afford.learning import load_model
    from afford.learn.affordances import predictor_inputs
    from afford.learn.predictors import AffordancePredictor

    model = load_model(args.model)
    data = interactions_from_artifact(read_artifact(args.data, "interactions"))
    test = interactions_from_artifact(read_artifact(args.test, "interactions"))
    sizes = [int(s) for s in args.sizes.split(",")]

    def labelled(d, name):
        rows = np.flatnonzero(d.behavior == d.behavior_names.index(name))
        y = model.effects[name].assign(d.effects_of(rows))
        keep = y >= 0  # effects of a kind the model discarded are not counted
        X = predictor_inputs(d.before_rows(rows[keep]), d.params[rows[keep]], model.selected[name], model.parameters(name))
        return X, y[keep]

    result: dict = {"model": args.model, "data": args.data, "test": args.test, "behaviors": {}}
    for name in model.names:
        X, y = labelled(data, name)
        Xt, yt = labelled(test, name)
        curve = []
        for n in sizes:
            n = min(n, len(y))
            t0 = time.perf_counter()
            predictor = AffordancePredictor(random_state=0).fit(X[:n], y[:n])
            curve.append({"rows": n, "accuracy": round(float(np.mean(predictor.predict(Xt) == yt)), 4),
                          "seconds": round(time.perf_counter() - t0, 1)})
            if n == len(y):
                break
        result["behaviors"][name] = {"n_test": int(len(yt)), "curve": curve}
    emit(result, args.out)


if __name__ == "__main__":
    main()
