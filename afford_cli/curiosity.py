"""Curiosity-driven exploration (thesis chapter 6): the robot scans candidate environments and
acts only where its learner finds the situation interesting.

Candidate ``i`` is the environment Algorithm 1's episode ``i`` would build, scanned once
(cheap: no physics). Then, per behaviour and independently (the thesis learned
go-forward; the other moves get the same treatment), :func:`afford.learn.online.learn_online`
walks the candidates in order: the first ``bootstrap`` are all tried, the rest only when
the strategy says so, and trying one runs the behaviour in PhysX from that environment's
start, in a world of its own (``sim.explore.try_candidate``), for the robot's own result.
Behaviours run on separate workers; the rows are the same for any number of them.

The interactions written hold every tried (candidate, behaviour) as a row with its given
result, so ``select-features``, ``train`` and ``evaluate`` take them as they take
Algorithm 1's; the manifest's ``online`` says how they were chosen, and the member
``online_tried`` (candidates x behaviours) which were tried and which skipped.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from afford.errors import AffordError

__all__ = ["explore_online", "online_members"]


def _learn_behaviour(scene, seed: int, X: np.ndarray, b: int, strategy: str, settings: dict,
                     X_test, y_test, in_worker: bool):
    from afford.learn.online import learn_online
    from afford.sim.explore import die_with_parent, try_candidate

    if in_worker:
        die_with_parent()
    tries: dict[int, tuple] = {}

    def label(i: int) -> int:
        tries[i] = try_candidate(scene, seed, i, b)
        return tries[i][0]

    run = learn_online(X, label, strategy, X_test=X_test, y_test=y_test, seed=seed, **settings)
    return b, run.tried, run.selected, run.curve, tries


def explore_online(scene, strategy: str = "margin", *, candidates: int = 3000, bootstrap: int = 25, tau: float = 0.5,
                   threshold: float = 0.7, budget: int | None = None, n_features: int = 250, every: int = 10,
                   test=None, seed: int = 0, workers: int = 1,
                   progress: Callable[[str, int, int], None] | None = None):
    """Curiosity-driven exploration of a scan scene (see the module docstring): returns the
    :class:`Interactions` of the tried (candidate, behaviour) pairs and a report (per
    behaviour how many were tried and skipped, and with ``test`` interactions of the same
    scene the learning curve ``[{"behavior", "interactions", "accuracy"}]``).
    ``progress(stage, done, total)`` hears the scanning and then each behaviour finished."""
    from afford.features import Interactions
    from afford.sim.explore import LocalPool, scan_candidates

    if scene.loop != "scan" or not scene.results:
        raise AffordError(f"curiosity-driven exploration needs a scene whose results are given, scanned once per "
                          f"environment (the traverse scenes); {scene.name!r} is not one")
    if not 2 <= bootstrap <= candidates:
        raise AffordError(f"--bootstrap must be between 2 and the {candidates} candidates, got {bootstrap}")
    if test is not None:
        if test.schema != scene.schema or test.result is None or test.behavior_names != [b.name for b in scene.behaviors]:
            raise AffordError("the test interactions are not of this scene's perception, behaviours and given results")
    X = scan_candidates(scene, candidates, seed=seed, workers=workers,
                        progress=None if progress is None else (lambda d, t: progress("scanning candidates", d, t)))
    settings = {"bootstrap": bootstrap, "tau": tau, "threshold": threshold, "budget": budget,
                "n_features": n_features, "every": every}
    B = len(scene.behaviors)

    def test_of(b):
        if test is None:
            return None, None
        rows = np.flatnonzero(test.behavior == b)
        return test.before_rows(rows), test.result[rows].astype(int)

    learned = {}
    if progress is not None:
        progress("learning behaviours", 0, B)
    with LocalPool(workers) as pool:
        tasks = [(scene, seed, X, b, strategy, settings, *test_of(b), pool.in_processes) for b in range(B)]
        for b, tried, selected, curve, tries in pool.run(_learn_behaviour, tasks):
            learned[b] = (tried, selected, curve, tries)
            if progress is not None:
                progress("learning behaviours", len(learned), B)
    pairs = sorted((i, b) for b in range(B) for i in learned[b][3])
    n_params = max((len(b.parameters) for b in scene.behaviors), default=0)
    params = np.zeros((len(pairs), n_params))
    truth_rows = []
    result = np.zeros(len(pairs), dtype=np.int8)
    for r, (i, b) in enumerate(pairs):
        res, alpha, truth = learned[b][3][i]
        result[r] = res
        params[r, : alpha.size] = alpha
        truth_rows.append(truth)
    keys = truth_rows[0].keys() if truth_rows else ()
    data = Interactions(
        schema=scene.schema, behaviors=[b.to_json() for b in scene.behaviors], entities=X,
        before_index=np.array([i for i, _ in pairs], dtype=np.int32), after_index=None,
        behavior=np.array([b for _, b in pairs], dtype=np.int16), params=params,
        episode=np.array([i for i, _ in pairs], dtype=np.int32), step=np.zeros(len(pairs), dtype=np.int16),
        result=result, result_names=list(scene.results),
        truth={k: np.array([t[k] for t in truth_rows]) for k in keys}, scene=scene.describe())
    tried = np.stack([learned[b][0] for b in range(B)], axis=1)
    names = [b.name for b in scene.behaviors]
    report = {
        "strategy": strategy, "candidates": candidates, **settings,
        "behaviors": {names[b]: {"tried": int(tried[:, b].sum()), "skipped": int(candidates - tried[:, b].sum()),
                                 "n_selected": int(len(learned[b][1]))} for b in range(B)},
    }
    if test is not None:
        report["curve"] = [{"behavior": names[b], **c} for b in range(B) for c in learned[b][2]]
    return data, tried, report


def online_members(data, tried: np.ndarray, report: dict):
    """The arrays and manifest of an online exploration's ``interactions`` artefact."""
    from afford.datasets import interactions_members

    arrays, meta = interactions_members(data)
    arrays["online_tried"] = tried
    meta["online"] = {k: v for k, v in report.items() if k != "curve"}
    return arrays, meta
