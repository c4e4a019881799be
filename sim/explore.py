"""Exploration: the robot acts in random worlds and records what happens.

Two loops, chosen by the scene (``scene.loop``):

``play`` (thesis Algorithm 5, chapter 8)
    Per episode (trial): a fresh world with one random object; while the object is
    visible and the last behaviour moved it (perceived), perceive, run a random behaviour
    with random parameters, perceive again, and record <f^(), b, alpha, f^(b)> with
    ground truth. Each look is stored once as an entity.
``scan`` (thesis Algorithm 1, chapter 5)
    Per episode: a random environment, scanned once (one entity); then every behaviour in
    turn, each from the same start in a freshly built world (the thesis's "reset robot
    and object positions"), recording <r, f, b> where r is the robot's own reading of
    whether the behaviour succeeded. Nothing is perceived after a behaviour.

Episode ``i`` draws everything from its own generator, seeded by ``(seed, i)``, so the
rows are the same whatever the number of workers and whichever worker ran the episode.
"""

from __future__ import annotations

import math
import os
import signal
import sys

from dataclasses import dataclass
from contextlib import nullcontext
from typing import Callable, Iterator, Mapping

import numpy as np

from afford.features import Interactions
from afford.features.errors import DataError
from afford.features.interactions import OUTCOMES
from afford.sim.objects import SHAPES
from afford.sim.world import LIFTED, ObjectTruth, outcome_label  # noqa: F401  (re-exported)

__all__ = ["explore", "LocalPool", "run_episode", "run_scan_episode", "interact", "Step", "episode_rng", "outcome_label",
           "MOVED", "LIFTED"]

#: A perceived position change above this (metres) counts as "the object moved".
MOVED = 0.015


def episode_rng(seed: int, episode: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(episode,)))


@dataclass(frozen=True)
class Step:
    """One interaction: the tracked objects before and after, and what physically happened."""

    before: np.ndarray                 # (k, d) perceived, tracked
    after: np.ndarray                  # (k, d)
    truth_before: list[ObjectTruth]    # in the order of the tracked objects
    truth_after: list[ObjectTruth]
    executed: bool                     # the arm reached and moved
    contact: bool                      # the hand touched an object
    outcomes: list[int]                # per tracked object, index into OUTCOMES


def interact(world, behavior, target: int, alpha: np.ndarray | None = None,
             before: np.ndarray | None = None) -> Step:
    """Run ``behavior`` on tracked object ``target`` (none, for a behaviour without a target),
    let the world settle, perceive again; the world names each tracked object's outcome
    (``world.outcomes``, indices into its scene's ``outcomes``)."""
    f0 = world.perceive() if before is None else before
    t0 = world.tracked_truth()
    world.contact = False
    execution = behavior(world, f0[target] if behavior.target is not None else None, alpha)
    world.settle()
    f1 = world.perceive()
    t1 = world.tracked_truth()
    return Step(f0, f1, t0, t1, execution.executed, world.contact, world.outcomes(t0, t1, f1))


@dataclass
class _Rows:
    behavior: list
    params: list
    step: list
    truth: dict


def run_episode(scene, seed: int, episode: int, max_steps: int | None = None) -> Interactions:
    """One episode of the scene's loop (``play`` or ``scan``) in fresh worlds; returns its rows."""
    if scene.loop == "scan":
        return run_scan_episode(scene, seed, episode)
    return run_play_episode(scene, seed, episode, scene.config.max_steps if max_steps is None else max_steps)


def run_play_episode(scene, seed: int, episode: int, max_steps: int = 10, only: int | None = None) -> Interactions:
    """One trial of Algorithm 5 in a fresh world; returns its rows. ``only``: run behaviour
    ``only`` once, its parameters from the trial's own generator (a curious robot trying
    candidate ``episode``), instead of random behaviours."""
    rng = episode_rng(seed, episode)
    specs = scene.sample(rng)
    spec = specs[0]
    world = scene.build(specs, rng)
    schema = scene.schema
    moving = schema.geometry
    behaviors = scene.behaviors
    n_params = max((len(b.parameters) for b in behaviors), default=0)
    # ground truth names a shape by its index into the scene's own shapes (every shape
    # afford knows for a scene that does not say)
    shapes = list(getattr(getattr(scene, "config", None), "shapes", SHAPES))
    rows = _Rows([], [], [], {k: [] for k in (
        "shape", "size", "pose_before", "pose_after", "in_hand_before", "in_hand_after",
        "reachable", "contact", "outcome")})
    f = world.perceive()
    looks = [f[0]] if f.shape[0] else []
    steps = 0
    while f.shape[0] and schema.visible(f[0]) and steps < (1 if only is not None else max_steps):
        b = int(rng.integers(len(behaviors))) if only is None else only
        behavior = behaviors[b]
        draw = rng if only is None else _try_rng(seed, episode, only)
        alpha = np.array([draw.uniform(p.low, p.high) for p in behavior.parameters], dtype=float)
        step = interact(world, behavior, 0, alpha, before=f)
        f1 = step.after
        t0, t1 = step.truth_before[0], step.truth_after[0]
        looks.append(f1[0])
        rows.behavior.append(b)
        padded = np.zeros(n_params)
        padded[: alpha.size] = alpha
        rows.params.append(padded)
        rows.step.append(steps)
        tr = rows.truth
        tr["shape"].append(shapes.index(spec.shape))
        size = np.full(3, np.nan)
        size[: len(spec.size)] = spec.size
        tr["size"].append(size)
        tr["pose_before"].append(np.concatenate([t0.position, t0.quaternion]))
        tr["pose_after"].append(np.concatenate([t1.position, t1.quaternion]))
        tr["in_hand_before"].append(t0.in_hand)
        tr["in_hand_after"].append(t1.in_hand)
        tr["reachable"].append(step.executed)
        tr["contact"].append(step.contact)
        tr["outcome"].append(step.outcomes[0])
        steps += 1
        moved = np.abs(f1[0, moving] - f[0, moving]).max() > MOVED
        f = f1
        if not moved:
            break
    n = len(rows.behavior)
    d = len(scene.schema)
    dtypes = {"shape": np.int8, "outcome": np.int8, "in_hand_before": bool, "in_hand_after": bool,
              "reachable": bool, "contact": bool}
    truth = {}
    for k, v in rows.truth.items():
        width = {"size": (3,), "pose_before": (7,), "pose_after": (7,)}.get(k, ())
        truth[k] = np.array(v, dtype=dtypes.get(k, np.float64)).reshape((n, *width))
    return Interactions(
        schema=scene.schema,
        behaviors=[b.to_json() for b in behaviors],
        entities=np.array(looks[: n + 1] if n else [], dtype=np.float32).reshape(n + 1 if n else 0, d),
        before_index=np.arange(n, dtype=np.int32),
        after_index=np.arange(1, n + 1, dtype=np.int32),
        behavior=np.array(rows.behavior, dtype=np.int16),
        params=np.array(rows.params, dtype=np.float64).reshape(n, n_params),
        episode=np.full(n, episode, dtype=np.int32),
        step=np.array(rows.step, dtype=np.int16),
        truth=truth,
        shapes=shapes,
        outcome_names=list(scene.outcomes),
        scene=scene.describe(),
    )


def run_scan_episode(scene, seed: int, episode: int, only: int | None = None) -> Interactions:
    """One trial of Algorithm 1: a random environment, scanned once, every behaviour tried
    from the same start in a freshly built world (``only``: behaviour ``only`` alone, its
    parameters from the trial's own generator: a curious robot trying candidate ``episode``).

    With given labels (chapter 5) the label is the robot's own reading and nothing is
    perceived after. With discovered labels (chapter 7) the robot looks again after each
    behaviour, tracking the first object it saw (the episode's one object), and the row's
    effect is that object's after - before."""
    rng = episode_rng(seed, episode)
    layout = scene.sample(rng)
    first = scene.build(layout, rng)
    entity = np.asarray(first.perceive(), dtype=np.float32)
    discovered = scene.labels == "discovered"
    behaviors = scene.behaviors if only is None else scene.behaviors[only:only + 1]
    behaviors = behaviors if not discovered or entity.shape[0] else ()
    n_params = max((len(b.parameters) for b in scene.behaviors), default=0)
    params, results, truth, after = [], [], [], []
    draw = rng if only is None else _try_rng(seed, episode, only)
    for behavior in behaviors:
        alpha = np.array([draw.uniform(p.low, p.high) for p in behavior.parameters], dtype=float)
        world = scene.build(layout, rng)
        if discovered:
            world.resume(first)
            step = interact(world, behavior, 0, alpha, before=entity.astype(np.float64))
            after.append(step.after[0])
            row = world.truth_row()
            row["outcome"] = np.int8(step.outcomes[0])
        else:
            results.append(behavior(world, None, alpha).result)
            row = world.truth_row()
        padded = np.zeros(n_params)
        padded[: alpha.size] = alpha
        params.append(padded)
        truth.append(row)
    n = len(behaviors)
    d = len(scene.schema)
    if not truth:  # nothing seen: no rows, but the same truth fields as every other episode
        row = first.truth_row()
        if discovered:
            row["outcome"] = np.int8(0)
        fields = {k: np.zeros((0, *np.shape(v)), dtype=np.asarray(v).dtype) for k, v in row.items()}
    else:
        fields = {k: np.array([t[k] for t in truth]) for k in truth[0]}
    entities = entity[:1].reshape(-1, d) if discovered else entity.reshape(1, -1)
    if discovered:
        entities = np.concatenate([entities, np.asarray(after, dtype=np.float32).reshape(n, d)])
    return Interactions(
        schema=scene.schema,
        behaviors=[b.to_json() for b in scene.behaviors],
        entities=entities,
        before_index=np.zeros(n, dtype=np.int32),
        after_index=np.arange(1, n + 1, dtype=np.int32) if discovered else None,
        behavior=np.array([scene.behaviors.index(b) for b in behaviors], dtype=np.int16),
        params=np.array(params, dtype=np.float64).reshape(n, n_params),
        episode=np.full(n, episode, dtype=np.int32),
        step=np.zeros(n, dtype=np.int16),
        result=None if discovered else np.array(results, dtype=np.int8),
        result_names=list(scene.results),
        truth=fields,
        shapes=list(SHAPES) if discovered else [],
        outcome_names=list(scene.outcomes),
        scene=scene.describe(),
    )


def die_with_parent() -> None:
    """In a worker process: ask Linux to kill it when its parent dies (``PR_SET_PDEATHSIG``),
    so that a ``kill -9`` of afford leaves no idle workers behind (elsewhere: nothing)."""
    global _ASKED
    if _ASKED or not sys.platform.startswith("linux"):
        return
    try:
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        libc.prctl(1, int(signal.SIGKILL), 0, 0, 0)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):  # pragma: no cover - no prctl: nothing to ask
        return
    _ASKED = True
    if os.getppid() == 1:  # the parent died before we asked
        os._exit(1)


_ASKED = False


def _run_chunk(scene, seed: int, episodes: list[int], max_steps: int | None,
               in_worker: bool = False) -> list[tuple[int, Interactions]]:
    """Run some episodes (in a worker process, or here); returns ``(episode, rows)`` pairs."""
    if in_worker:
        die_with_parent()
    return [(e, run_episode(scene, seed, e, max_steps)) for e in episodes]


def _chunks(episodes: list[int], size: int) -> Iterator[list[int]]:
    for a in range(0, len(episodes), size):
        yield episodes[a:a + size]


class LocalPool:
    """Where episodes run on this machine: here (one worker) or on joblib's loky processes.

    A pool runs tasks with :meth:`run` and yields each result as it finishes, in any order
    (exploration puts episodes back in order itself). Other pools (afford's Dask pool) have
    the same three members: ``workers``, ``in_processes`` and ``run``.
    """

    def __init__(self, workers: int = 1):
        self.workers = workers
        self.in_processes = workers > 1  # tasks run in worker processes this pool started
        self._parallel = None

    def __enter__(self) -> "LocalPool":
        if self.workers > 1:
            from joblib import Parallel

            self._parallel = Parallel(n_jobs=self.workers, return_as="generator_unordered")
            self._parallel.__enter__()
        return self

    def __exit__(self, *exc) -> None:
        if self._parallel is not None:
            self._parallel.__exit__(*exc)
            self._parallel = None

    def run(self, fn: Callable, tasks: list[tuple]) -> Iterator:
        if self._parallel is None:
            for task in tasks:
                yield fn(*task)
            return
        import warnings

        from joblib import delayed

        results = self._parallel(delayed(fn)(*task) for task in tasks)
        try:
            for result in results:  # not ``yield from``: that would close ``results`` outside the filter below
                yield result
        finally:
            with warnings.catch_warnings():  # an interrupted run cancels its tasks on purpose
                warnings.filterwarnings("ignore", message=".*tasks which were still being processed", category=UserWarning)
                results.close()


def explore(
    scene,
    *,
    episodes: int | None = None,
    interactions: int | None = None,
    seed: int = 0,
    workers: int = 1,
    max_steps: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    chunk: int | None = None,
    episode_start: int = 0,
    done: Mapping[int, Interactions] | None = None,
    on_done: Callable[[list[tuple[int, Interactions]]], None] | None = None,
    pool=None,
) -> Interactions:
    """Run exploration episodes; stop after ``episodes`` or once ``interactions`` rows exist.

    Episodes ``episode_start`` .. ``episode_start + episodes - 1`` run (a shard of a larger
    exploration when ``episode_start`` > 0); with ``interactions`` they run from episode 0
    on until enough rows exist, and the result is cut to exactly that many rows in episode
    order. Either way the rows are the same for any number of workers, any pool and any
    order in which episodes finish.

    ``done`` holds episodes already finished (a journal's, when a run resumes): they are not
    run again. ``on_done(pairs)`` is called with each batch of newly finished ``(episode,
    rows)`` pairs as it arrives, ``progress(done, total)`` after it (in episodes, or in rows
    when ``interactions`` is given). ``pool`` runs the episodes (a :class:`LocalPool` of
    ``workers`` by default); ``chunk`` episodes go to a task (8 at the table, 1 in scans).
    """
    if (episodes is None) == (interactions is None):
        raise DataError("give either episodes or interactions")
    if interactions is not None and episode_start:
        raise DataError("an exploration to a number of interactions starts at episode 0; shard one by episodes")
    chunk = chunk or (1 if scene.loop == "scan" else 8)
    first = episode_start
    finished: dict[int, Interactions] = {}
    last = first + episodes if episodes is not None else None
    count = 0  # finished episodes of the range, or rows of finished episodes from ``first`` on

    def keep(pairs) -> None:
        nonlocal count
        for e, part in pairs:
            if e in finished or e < first or (last is not None and e >= last):
                continue
            finished[e] = part
            count += 1 if episodes is not None else len(part)

    keep((done or {}).items())
    own = pool is None
    pool = LocalPool(workers) if own else pool
    target = episodes if episodes is not None else interactions
    show = (lambda: progress(min(count, target), target)) if progress is not None else (lambda: None)
    total_rows = 0
    next_episode = first
    with pool if own else nullcontext(pool):
        show()
        while True:
            if episodes is not None:
                if next_episode >= last:
                    break
                stop = last
            else:
                if total_rows >= interactions:
                    break
                # Ask for about as many episodes as the rows still missing need, at the rate
                # seen so far, so little is explored in vain. A scan yields every behaviour
                # once; a play episode yields as many rows as the object keeps moving (about
                # 2 at the table, 6-7 with the hand), so the first batch only measures it.
                if next_episode > first:
                    rate = total_rows / (next_episode - first)
                elif scene.loop == "scan":
                    rate = float(len(scene.behaviors))
                else:
                    rate = math.inf
                need = max(pool.workers * chunk, int((interactions - total_rows) / max(rate, 1.0)) + 1)
                stop = next_episode + need
            todo = [e for e in range(next_episode, stop) if e not in finished]
            tasks = [(scene, seed, eps, max_steps, pool.in_processes) for eps in _chunks(todo, chunk)]
            for result in pool.run(_run_chunk, tasks):
                keep(result)
                if on_done is not None:
                    on_done(result)
                show()
            total_rows += sum(len(finished[e]) for e in range(next_episode, stop))
            next_episode = stop
    data = Interactions.concatenate([finished[e] for e in range(first, next_episode)])
    if interactions is not None:
        data = data.subset(np.arange(interactions))
    return data



# -- candidates for curiosity-driven exploration (thesis chapter 6) --------------------------

def _try_rng(seed: int, candidate: int, behavior: int) -> np.random.Generator:
    return np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(candidate, 1 + behavior)))


def scan_candidate(scene, seed: int, candidate: int) -> np.ndarray:
    """Candidate ``candidate`` of a scene's stream, looked at once (no physics): its entity
    (d,), what the scene's episode of that number perceives first. In a scene whose
    results are given, the environment's scan; in one that discovers its categories, the
    first object seen (all NaN when none is seen: no situation to learn from)."""
    rng = episode_rng(seed, candidate)
    layout = scene.sample(rng)
    seen = np.asarray(scene.build(layout, rng).perceive(), dtype=np.float32)
    if scene.labels == "given":
        return seen[0]
    if seen.shape[0] and scene.schema.visible(seen[0]):
        return seen[0]
    return np.full(len(scene.schema), np.nan, dtype=np.float32)


def try_candidate_effect(scene, seed: int, candidate: int, behavior: int) -> Interactions:
    """Run behaviour ``behavior`` on candidate ``candidate``'s object (a scene that
    discovers its categories), from the start its episode perceives (the same look as
    :func:`scan_candidate`): one row of interactions with its effect and ground truth (none
    when nothing is seen). Every (candidate, behaviour) draws its parameters from its own
    generator, so the row does not depend on what else was tried."""
    if scene.loop == "scan":
        return run_scan_episode(scene, seed, candidate, only=behavior)
    return run_play_episode(scene, seed, candidate, only=behavior)


def try_candidate(scene, seed: int, candidate: int, behavior: int) -> tuple[int, np.ndarray, dict]:
    """Run behaviour ``behavior`` in candidate ``candidate``'s environment, in a fresh world
    from its start: (the robot's own result, alpha, ground truth). Every (candidate,
    behaviour) has its own generator, so the outcome does not depend on what else was tried."""
    layout = scene.sample(episode_rng(seed, candidate))
    rng = _try_rng(seed, candidate, behavior)
    b = scene.behaviors[behavior]
    alpha = np.array([rng.uniform(p.low, p.high) for p in b.parameters], dtype=float)
    world = scene.build(layout, rng)
    execution = b(world, None, alpha)
    return int(execution.result), alpha, world.truth_row()


def _scan_chunk(scene, seed: int, candidates: list[int], in_worker: bool = False) -> list[tuple[int, np.ndarray]]:
    if in_worker:
        die_with_parent()
    return [(c, scan_candidate(scene, seed, c)) for c in candidates]


def scan_candidates(scene, n: int, *, seed: int = 0, pool=None, workers: int = 1,
                    progress: Callable[[int, int], None] | None = None) -> np.ndarray:
    """The entities (n, d) of candidates 0 .. n-1 (:func:`scan_candidate`), looked at on
    ``pool`` (any order, put back in order)."""
    out: dict[int, np.ndarray] = {}
    own = pool is None
    pool = LocalPool(workers) if own else pool
    with pool if own else nullcontext(pool):
        tasks = [(scene, seed, c, pool.in_processes) for c in _chunks(list(range(n)), 4)]
        for result in pool.run(_scan_chunk, tasks):
            out.update(result)
            if progress is not None:
                progress(len(out), n)
    return np.stack([out[c] for c in range(n)]) if n else np.zeros((0, len(scene.schema)), dtype=np.float32)
