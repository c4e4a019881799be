"""How predictable are a model's effect categories at all? The same SVM on ground truth.

    python benchmarks/ceiling.py --model M --data TRAIN --test TEST [--test TEST2 ...]

Labels the rows of the training and test interactions with the model's effect categories
(``EffectCategories.assign``, as ``afford evaluate`` does) and trains, per behaviour, the
same calibrated SVM (``learn.predictors.AffordancePredictor``) and a random forest on what
physically was before each interaction instead of on what the robot perceived: the
object's true position, yaw (as cos and sin of 2 and 4 times it, the symmetries of boxes
and cylinders), true size, shape and whether it was in the hand. It prints, per behaviour
and test file, the held-out accuracy of those two next to the model's own predictor.

Ground truth is used here to measure the world, never to learn a model the robot uses:
where even the true state predicts the categories no better than perception does, the
limit is the world's physics and the amount of data, not perception or the learner. Not
part of ``make bench`` (it needs a model and its training data).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from benchmarks._common import emit  # noqa: E402


def true_state(data, rows: np.ndarray) -> np.ndarray:
    """What physically was before each row: position, yaw symmetries, size, shape, in hand."""
    truth = data.truth
    pose = truth["pose_before"][rows]
    w, x, y, z = pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]
    yaw = np.arctan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))
    shape = np.eye(len(data.shapes))[truth["shape"][rows]]
    size = np.nan_to_num(truth["size"][rows], nan=0.0)
    turns = [f(k * yaw) for k in (2, 4) for f in (np.cos, np.sin)]
    return np.column_stack([pose[:, :3], *turns, size, shape, truth["in_hand_before"][rows]])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--model", required=True, help="a model artefact (its categories are the targets)")
    ap.add_argument("--data", required=True, help="the interactions the model was trained on")
    ap.add_argument("--test", required=True, action="append", help="held-out interactions (repeat for several)")
    ap.add_argument("--out", default="benchmarks/results/ceiling.json")
    args = ap.parse_args()

    from sklearn.ensemble import RandomForestClassifier

    from afford.artifacts import read_artifact
    from afford.datasets import interactions_from_artifact
    from afford.learning import load_model
    from afford.learn.affordances import predictor_inputs
    from afford.learn.predictors import AffordancePredictor

    model = load_model(args.model)
    data = interactions_from_artifact(read_artifact(args.data, ("interactions", "effects", "features")))
    tests = {t: interactions_from_artifact(read_artifact(t, ("interactions", "effects", "features"))) for t in args.test}

    def labelled(d, name):
        rows = np.flatnonzero(d.behavior == d.behavior_names.index(name))
        y = model.effects[name].assign(d.effects_of(rows))
        rows, y = rows[y >= 0], y[y >= 0]  # effects of a kind the model discarded are not counted
        perceived = predictor_inputs(d.before_rows(rows), d.params[rows], model.selected[name], model.parameters(name))
        return perceived, true_state(d, rows), y

    result: dict = {"model": args.model, "data": args.data, "behaviors": {}}
    for name in model.names:
        _, S, y = labelled(data, name)
        svm = AffordancePredictor(random_state=0).fit(S, y)
        forest = RandomForestClassifier(n_estimators=300, min_samples_leaf=2, random_state=0).fit(S, y)
        per_test = {}
        for path, test in tests.items():
            Xt, St, yt = labelled(test, name)
            per_test[path] = {
                "n_test": int(yt.size),
                "perceived_model": round(float(np.mean(model.predictors[name].predict(Xt) == yt)), 4),
                "true_state_svm": round(float(np.mean(svm.predict(St) == yt)), 4),
                "true_state_forest": round(float(np.mean(forest.predict(St) == yt)), 4),
            }
        result["behaviors"][name] = {"n_train": int(y.size), "true_state_svm_cv": round(svm.cv_report_["cv_accuracy"], 4),
                                     "tests": per_test}
    emit(result, args.out)


if __name__ == "__main__":
    main()
