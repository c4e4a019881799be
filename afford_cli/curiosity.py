"""Curiosity-driven exploration (thesis chapter 6): the robot looks at candidate situations and
acts only where its learner finds the situation interesting.

Candidate ``i`` is what the scene's episode ``i`` would perceive first, looked at once
(cheap: no physics): in a scene whose results are given (the traverse scenes), the
environment Algorithm 1's episode ``i`` builds, scanned; in a scene that discovers its
effect categories (the table), the one object episode ``i`` puts before the robot.
Then, per behaviour and independently (the thesis learned go-forward; the other moves
get the same treatment), :func:`afford.learn.online.learn_online` walks the candidates
in order: the first ``bootstrap`` are all tried, the rest only when the strategy says
so, and trying one runs the behaviour in PhysX from that candidate's start, in a world
of its own (``sim.explore.try_candidate``, ``try_candidate_effect``), for the robot's
own result, or for the effect it then perceives. With discovered categories the robot
clusters its bootstrap's effects once, with the scene's clustering (as ``afford
cluster`` does), and names every later effect, and the test set's, by the nearest of
those categories: the curiosity is over calibrated probabilities of effect categories
(beyond the thesis, whose chapter 6 had given labels only). Behaviours run on separate
workers; the rows are the same for any number of them.

The interactions written hold every tried (candidate, behaviour) as a row with its given
result (or its effect), so ``select-features``, ``train`` and ``evaluate`` (or
``cluster`` first) take them as they take the scene's own loop's; the manifest's
``online`` says how they were chosen, and the member ``online_tried`` (candidates x
behaviours) which were tried and which skipped.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from afford.errors import AffordError

__all__ = ["categoriser", "explore_online", "online_members"]


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
    return b, run.tried, run.selected, run.curve, tries, 2


def categoriser(scene, clustering: dict, b: int, seed: int, looks: np.ndarray):
    """``categorise(outcomes, rows)`` for :func:`afford.learn.online.learn_online`: behaviour
    ``b``'s categories found once in the bootstrap's effects (candidates ``rows`` of the
    stream whose looks are ``looks``) with the scene's ``clustering``, and ``found``, which
    then holds them (``"categories"``). A category needs 3 of the bootstrap's effects
    (else it is pruned and its effects go to the nearest kept one): fewer cannot be
    calibrated out of fold, and an uncalibrated learner finds every candidate interesting."""
    from afford.learn.affordances import effect_categories, k_per_behaviour

    found: dict = {}

    def categorise(outcomes, rows):
        names = [x.name for x in scene.behaviors]
        k = k_per_behaviour(clustering["k"], names)[names[b]]
        ec = effect_categories(scene.schema, np.stack(outcomes), looks[np.asarray(rows)].astype(np.float64), b,
                               method=clustering["method"], k_max=clustering["k_max"], k=k, seed=seed,
                               channels=clustering["channels"], min_fraction=max(0.03, 3 / len(rows)))
        found["categories"] = ec
        return lambda E: ec.predict(np.asarray(E, dtype=np.float64).reshape(len(E), -1))

    return categorise, found


def _learn_categories(scene, seed: int, X: np.ndarray, b: int, strategy: str, settings: dict,
                      X_test, E_test, in_worker: bool):
    """One behaviour's curiosity over discovered effect categories (see the module docstring)."""
    from afford.learn.online import learn_online
    from afford.sim.explore import die_with_parent, try_candidate_effect

    if in_worker:
        die_with_parent()
    settings = dict(settings)
    seen = np.flatnonzero(np.isfinite(X).all(axis=1))  # candidates with an object in view
    categorise, found = categoriser(scene, settings.pop("clustering"), b, seed, X[seen])
    tries: dict = {}

    def label(j: int) -> np.ndarray:
        i = int(seen[j])
        tries[i] = try_candidate_effect(scene, seed, i, b)
        return tries[i].effects_of(np.zeros(1, dtype=int))[0]

    run = learn_online(X[seen], label, strategy, categorise=categorise, X_test=X_test,
                       y_test=None if E_test is None else list(E_test), seed=seed, **settings)
    tried = np.zeros(len(X), dtype=bool)
    tried[seen] = run.tried
    return b, tried, run.selected, run.curve, tries, int(found["categories"].n_categories_)


def explore_online(scene, strategy: str = "margin", *, candidates: int = 3000, bootstrap: int = 25, tau: float = 0.5,
                   threshold: float = 0.7, budget: int | None = None, n_features: int = 250, every: int = 10,
                   test=None, seed: int = 0, workers: int = 1,
                   progress: Callable[[str, int, int], None] | None = None):
    """Curiosity-driven exploration (see the module docstring): returns the
    :class:`Interactions` of the tried (candidate, behaviour) pairs, which of the
    candidates x behaviours were tried, and a report (per behaviour how many were tried
    and skipped, and with ``test`` interactions of the same scene the learning curve
    ``[{"behavior", "interactions", "accuracy"}]``). ``progress(stage, done, total)``
    hears the looking and then each behaviour finished."""
    from afford.sim.explore import LocalPool, scan_candidates

    discovered = scene.labels == "discovered"
    if not discovered and scene.loop != "scan":
        raise AffordError(f"curiosity-driven exploration of given results needs a scene scanned once per environment "
                          f"(the traverse scenes); {scene.name!r} is not one")
    if discovered and any(b.parameters for b in scene.behaviors):
        raise AffordError(f"curiosity-driven exploration of behaviours with parameters is not built; {scene.name!r} "
                          "has some (explore it with its own loop)")
    least = 10 if discovered else 2
    if not least <= bootstrap <= candidates:
        raise AffordError(f"--bootstrap must be between {least} and the {candidates} candidates, got {bootstrap}"
                          + (" (its effects are clustered into the categories)" if discovered else ""))
    names = [b.name for b in scene.behaviors]
    if test is not None:
        same = test.schema == scene.schema and test.behavior_names == names
        if not same or (test.result is None) != discovered or (discovered and not test.has_after):
            raise AffordError("the test interactions are not of this scene's perception, behaviours and "
                              + ("effects" if discovered else "given results"))
    X = scan_candidates(scene, candidates, seed=seed, workers=workers,
                        progress=None if progress is None else (lambda d, t: progress("looking at candidates", d, t)))
    situations = int(np.isfinite(X).all(axis=1).sum())  # candidates with something to act on
    if discovered and situations < bootstrap:
        raise AffordError(f"only {situations} of the {candidates} candidates show an "
                          f"object, fewer than the bootstrap of {bootstrap}; draw more --candidates")
    settings = {"bootstrap": bootstrap, "tau": tau, "threshold": threshold, "budget": budget,
                "n_features": n_features, "every": every}
    from afford.learning import learner_settings

    kernel, _ = learner_settings(None, scene.describe())
    B = len(scene.behaviors)

    def test_of(b):
        if test is None:
            return None, None
        rows = np.flatnonzero(test.behavior == b)
        if discovered:  # the situations candidates are: a fresh start, nothing in hand yet
            rows = rows[test.step[rows] == 0]
            if rows.size == 0:
                raise AffordError(f"the test interactions have no first step of behaviour {names[b]!r} to score it "
                                  "on; explore more episodes for the test")
            return test.before_rows(rows), test.effects_of(rows)
        return test.before_rows(rows), test.result[rows].astype(int)

    if discovered:
        from afford.learning import clustering_settings

        clustering = clustering_settings(scene.describe(), scene.schema, f"scene {scene.name!r}")
        fn, extra = _learn_categories, {"clustering": clustering}
    else:
        fn, extra = _learn_behaviour, {}
    learned = {}
    if progress is not None:
        progress("learning behaviours", 0, B)
    with LocalPool(workers) as pool:
        tasks = [(scene, seed, X, b, strategy, {**settings, "kernel": kernel, **extra}, *test_of(b), pool.in_processes)
                 for b in range(B)]
        for b, tried, selected, curve, tries, n_categories in pool.run(fn, tasks):
            learned[b] = (tried, selected, curve, tries, n_categories)
            if progress is not None:
                progress("learning behaviours", len(learned), B)
    pairs = sorted((i, b) for b in range(B) for i in learned[b][3])
    data = _tried_rows(scene, X, pairs, learned) if discovered else _given_rows(scene, X, pairs, learned)
    tried = np.stack([learned[b][0] for b in range(B)], axis=1)
    report = {
        "strategy": strategy, "candidates": candidates, **settings, "kernel": kernel,
        "behaviors": {names[b]: {"tried": int(tried[:, b].sum()), "skipped": int(situations - tried[:, b].sum()),
                                 "n_selected": int(len(learned[b][1])),
                                 **({"n_categories": learned[b][4]} if discovered else {})} for b in range(B)},
    }
    if discovered:
        report["with_object"] = situations
        report["clustering"] = clustering
    if test is not None:
        report["curve"] = [{"behavior": names[b], **c} for b in range(B) for c in learned[b][2]]
    return data, tried, report


def _given_rows(scene, X: np.ndarray, pairs: list[tuple[int, int]], learned: dict):
    """The tried pairs' rows with their given results; candidate ``i``'s scan is entity ``i``."""
    from afford.features import Interactions

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
    return Interactions(
        schema=scene.schema, behaviors=[b.to_json() for b in scene.behaviors], entities=X,
        before_index=np.array([i for i, _ in pairs], dtype=np.int32), after_index=None,
        behavior=np.array([b for _, b in pairs], dtype=np.int16), params=params,
        episode=np.array([i for i, _ in pairs], dtype=np.int32), step=np.zeros(len(pairs), dtype=np.int16),
        result=result, result_names=list(scene.results),
        truth={k: np.array([t[k] for t in truth_rows]) for k in keys}, scene=scene.describe())


def _tried_rows(scene, X: np.ndarray, pairs: list[tuple[int, int]], learned: dict):
    """The tried pairs' rows with their effects: each tried candidate's look stored once,
    then each row's look after."""
    from afford.features import Interactions

    rows = Interactions.concatenate([learned[b][3][i] for i, b in pairs])
    looked = sorted({i for i, _ in pairs})
    at = {c: k for k, c in enumerate(looked)}
    rows.entities = np.concatenate([X[looked], rows.entities[rows.after_index]]).astype(np.float32)
    rows.before_index = np.array([at[i] for i, _ in pairs], dtype=np.int32)
    rows.after_index = np.arange(len(looked), len(looked) + len(pairs), dtype=np.int32)
    rows.validate()
    return rows


def online_members(data, tried: np.ndarray, report: dict):
    """The arrays and manifest of an online exploration's ``interactions`` artefact."""
    from afford.datasets import interactions_members

    arrays, meta = interactions_members(data)
    arrays["online_tried"] = tried
    meta["online"] = {k: v for k, v in report.items() if k != "curve"}
    return arrays, meta
