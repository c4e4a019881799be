"""Planning in a scene, as ``plan``, ``emulate`` and the benchmarks run it."""

from __future__ import annotations

import time
from contextlib import contextmanager, nullcontext

from afford.scenes_io import open_world

__all__ = ["plan_once", "draw_plan", "progress_bars", "PROGRESS_AFTER"]

#: Seconds a search or an assessment runs before its progress bar appears.
PROGRESS_AFTER = 2.0


def progress_bars(output, after: float | None = None):
    """What :func:`afford.plan.search.watching` takes: a progress bar on ``output``'s stderr
    (an :class:`afford.output.Output`) for each search or assessment of candidate plans that
    runs longer than ``after`` seconds (:data:`PROGRESS_AFTER`); quicker ones leave stderr
    as it was. A search's bar counts nodes expanded against the node budget, and ends at
    the count it stopped at; an assessment's counts imagined runs."""

    @contextmanager
    def bar(description: str, total: int):
        t0, shown, last = time.monotonic(), False, 0
        wait = PROGRESS_AFTER if after is None else after
        with output.progress(description, total, lazy=True) as update:
            def tick(done: int) -> None:
                nonlocal shown, last
                last = done
                if shown or time.monotonic() - t0 >= wait:
                    shown = True
                    update(done)

            yield tick
            if shown:
                update(last, max(last, 1))  # a search that ended before its budget: the bar is full

    return bar


def plan_once(model, scene, specs, seed: int, goal, method: str, limits: dict, execute: bool, max_replans: int,
              alternatives: int = 3, say=None, plot: str | None = None, progress=None, blind_rollouts: int = 0) -> dict:
    """Plan in one scene (and execute with monitoring); the result as plain data.

    With ``alternatives`` > 1 the most probable plans are ranked by their success
    probability with monitoring, the first is the plan (and every replan is chosen the same
    way), and the others are reported under ``alternatives``. ``say(line)`` hears the
    search start and, when executing, each step and replan as it happens. ``progress``:
    what :func:`afford.plan.search.watching` takes (:func:`progress_bars`), told how each
    search and assessment goes. ``plot``: a PNG of the start's range image and the scene
    from above (:func:`draw_plan`).

    Time: ``planning_seconds`` is the whole of finding the plan, ``search_seconds`` and
    ``assess_seconds`` its two parts (the search for the candidates; their imagined runs,
    which give each one's success probability with monitoring, and are most of it); each
    plan's own ``seconds`` is the search up to it. ``execution_seconds``: running it, with
    every replan's search and assessment. ``blind_rollouts``: also the plan's
    ``blind_probability`` (:meth:`afford.api.Model.blind_probability`, seeded by the scene's
    seed) from that many imagined blind runs.
    """
    from afford.plan.search import watching

    world = open_world(scene, specs, seed)
    start = world.perceive()
    model.check_schema(scene.schema, "this scene's perception")
    if say is not None:
        say(f"searching for a plan ({alternatives} candidate{'s' * (alternatives != 1)}, ranked by success probability)")
    def watched():
        return nullcontext() if progress is None else watching(progress)

    t0 = time.perf_counter()
    with watched():
        ranked = model.plans(start, goal, alternatives=alternatives, max_replans=max_replans, method=method, **limits)
    planning = time.perf_counter() - t0
    assessing = sum(p.assess_seconds for p in ranked)
    first = ranked[0]
    out = {"seed": seed, "objects": start.shape[0], "plan": first.to_json(), "tree": first.tree[:12],
           "planning_seconds": round(planning, 4), "search_seconds": round(planning - assessing, 4),
           "assess_seconds": round(assessing, 4)}
    if alternatives > 1:
        out["alternatives"] = [p.to_json() for p in ranked[1:]]
    if blind_rollouts and first.found:  # before execution: the world is still at the start
        out["plan"]["blind_probability"] = round(model.blind_probability(start, goal, first, rollouts=blind_rollouts,
                                                                         seed=seed), 4)
        out["plan"]["blind_rollouts"] = blind_rollouts
    if execute and first.found:
        t0 = time.perf_counter()
        with watched():
            result = model.execute(world, goal, first=first, alternatives=alternatives, max_replans=max_replans,
                                   method=method, say=say, **limits)
        out["execution_seconds"] = round(time.perf_counter() - t0, 4)
        out["execution"] = result.to_json()
        out["reached"] = result.reached
        out["replans"] = result.replans
        # did the first plan, as planned, work without replanning?
        out["first_plan_worked"] = result.reached and result.replans == 0 and result.windfalls == 0
    if plot is not None:
        reached = f"; reached: {'yes' if out['reached'] else 'no'}" if "reached" in out else ""
        out["plot"] = draw_plan(plot, model.schema, world, start, first, world.perceive() if "execution" in out else None,
                                f"plan for {' and '.join(goal.to_json())}{reached}")
    return out


def draw_plan(path: str, schema, world, start, plan, actual=None, title: str = "", shown=None) -> str:
    """The start's range image, and the scene from above: where each object started, where
    the plan's last step is predicted to leave it, and (executed) where it really ended."""
    from afford.plots import scene_figure

    predicted = plan.steps[-1].predicted if plan.found and plan.steps else None
    steps = ", ".join(f"{s.behavior} {s.obj}" for s in plan.steps) if plan.found else "no plan found"
    panel = {"title": f"from above: {steps}", "start": start, "predicted": predicted, "actual": actual, "shown": shown}
    return scene_figure(path, schema, view=getattr(world, "start_view", None), panels=[panel], title=title)
