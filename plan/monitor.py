"""Executing a plan and watching it (thesis 7.6 and 8.6): act, perceive, compare, replan.

The planner talks to the world through the small :class:`World` protocol, which the
simulator implements (``sim.session.SimWorld``); ``plan`` never imports ``sim``. The world
keeps track of which perceived object is which, so a step's prediction is compared with
the perception of the same objects. When a perceived outcome differs from the predicted one
on the goal's channels, the robot replans from what it perceives, up to ``max_replans`` times
(and up to as many more after surprises that left the world nearer the goal than predicted),
and a behaviour that already surprised it on an object costs more in the new search (the same
prediction would otherwise send it round in circles). The robot knows which object its hand
holds (one a step raised) and replans with it.

:func:`reach_probability` runs the same executor in worlds drawn from the model, to tell how
likely a plan is to reach its goal when it is run this way (:func:`blind_probability`, when
it is run blind); :func:`assess` stores that on
the plan next to its open-loop probability, and :func:`rank_plans` orders the most probable
plans by it. When the world says its arm did not start (the object lay beyond reach), the
robot leaves that object alone where it lies.
"""

from __future__ import annotations

import time
from contextlib import nullcontext
from dataclasses import dataclass, field
from typing import Callable, Protocol

import numpy as np

from afford.plan.forward import ForwardModel, one_blas_thread
from afford.plan.forward import SCENE
from afford.plan.goals import Goal
from afford.plan.search import UNREACHABLE, Plan, best_plans, phase, search, situation, unwatched

__all__ = ["World", "Execution", "assess", "blind_probability", "execute", "mismatch", "rank_plans", "reach_probability", "ranked_planner"]


class World(Protocol):
    """What the executor needs of a world: perceive, and act on a perceived object.

    A world may also say whether its arm carried out the last behaviour, as
    ``last_executed`` (a bool): an arm does not start a behaviour aimed beyond its reach,
    and a robot knows when its own arm did not move. Worlds without it are taken to have
    moved every time.
    """

    def perceive(self) -> np.ndarray: ...

    def act(self, behavior: str, target: int, alpha: np.ndarray | None = None) -> np.ndarray: ...


@dataclass
class Execution:
    reached: bool
    plans: list[Plan] = field(default_factory=list)
    executed: list[dict] = field(default_factory=list)  # every step run, with what was perceived
    replans: int = 0
    reason: str = ""
    windfalls: int = 0  # replans after a surprise that left the world nearer the goal than predicted

    def to_json(self) -> dict:
        return {"reached": self.reached, "replans": self.replans, "windfalls": self.windfalls, "reason": self.reason,
                "executed": self.executed, "plans": [p.to_json() for p in self.plans]}


def mismatch(goal: Goal, predicted: np.ndarray, perceived: np.ndarray, schema, slack: float = 1.6) -> str:
    """Why the perceived state differs from the predicted one on the goal's channels ('' if not).

    The schema says what to compare: visibility (seen or gone), then each constrained
    channel's features, allowed ``slack`` times their goal tolerance for measurements
    (8 cm of the table's positions) and twice it for histogram bins.
    """
    channels = goal.channels
    vis = schema.visibility_index
    vis_channel = None if vis is None else schema.channels[vis]
    measured = {ch: idx for ch, idx in schema.channel_groups()}
    # a flip of visibility matters to goals on visibility or on measurements (not on histograms alone)
    flips = vis is not None and (vis_channel in channels or any(
        not schema.in_histogram[measured[ch]].all() for ch in channels if ch in measured and ch != vis_channel))
    seen_p, seen_q = schema.visible(predicted), schema.visible(perceived)
    for i in range(min(predicted.shape[0], perceived.shape[0])):
        if flips:
            if seen_p[i] != seen_q[i]:
                return f"object {i} is {'gone' if not seen_q[i] else 'still there'}, unlike predicted"
        if not seen_q[i]:
            continue
        for ch in sorted(channels):
            idx = measured.get(ch)
            if idx is None or ch == vis_channel:
                continue
            in_hist = schema.in_histogram[idx]
            tol = schema.channel(ch).tolerance * np.where(in_hist, 2.0, slack)
            gap = np.abs(predicted[i, idx] - perceived[i, idx])
            if (gap > tol).any():
                if in_hist.all():
                    return f"object {i} looks different from predicted"
                unit = schema.channel(ch).unit
                return f"object {i} ended {float(gap.max()):.2f}{(' ' + unit) if unit else ''} from where it was predicted"
    return ""


@one_blas_thread
def execute(world: World, model: ForwardModel, goal: Goal, *, method: str = "best-first", max_replans: int = 3,
            first: Plan | None = None, planner: Callable[[np.ndarray, tuple, int], Plan] | None = None,
            say: Callable[[str], None] | None = None, **limits) -> Execution:
    """Plan (unless ``first`` is given), execute step by step, replan on surprises.

    ``planner(state, avoid, held)`` replaces the search (with ``method`` and ``limits``)
    where given. The robot keeps track of what its hand holds (an object a step raised) and
    replans with it. ``say(line)``, if given, hears what is going on: each step as it starts
    and how it went, each replan as its search starts.
    """
    say = say or (lambda line: None)
    if planner is None:
        def planner(state: np.ndarray, avoid: tuple, held: int) -> Plan:
            return search(model, state, goal, method, avoid=avoid, held=held, **limits)

    state = world.perceive()
    held = -1
    if first is None:
        say("searching for a plan")
    plan = first if first is not None else planner(state, (), held)
    run = Execution(False, [plan])
    # (object seen before, behaviour, object, whether the hand held it) of steps that surprised
    failed: list[tuple[np.ndarray, str, int, bool]] = []
    out_of_reach = ""
    while True:
        if not plan.found:
            run.reason = f"no plan found ({plan.reason}{'; ' + out_of_reach if out_of_reach else ''})"
            return run
        if goal.holds(state):
            run.reached = True
            run.reason = "goal reached"
            return run
        surprised, windfall = "", False
        for k, step in enumerate(plan.steps, 1):
            previous, was_held = state, held == step.obj
            before = situation(model, state, step.obj)
            on = "the scene" if step.obj == SCENE else f"object {step.obj}"
            say(f"executing step {k} of {len(plan.steps)}{f' (plan {len(run.plans)})' if len(run.plans) > 1 else ''}: "
                f"{step.behavior} on {on}")
            state = world.act(step.behavior, step.obj, np.asarray(step.alpha, dtype=float))
            held = step.obj if model.in_hand(previous, state, step.obj) else -1
            if not getattr(world, "last_executed", True):
                # The arm did not start: the object lies beyond its reach, and no behaviour
                # will do anything to it there (every plan step expected some change).
                surprised = out_of_reach = f"the arm cannot reach object {step.obj} where it lies"
                failed.append((before, UNREACHABLE, step.obj, was_held))
            else:
                surprised = mismatch(goal, step.predicted, state, model.schema)
                if surprised:
                    failed.append((before, step.behavior, step.obj, was_held))
            run.executed.append({**step.to_json(), "as_predicted": not surprised, "note": surprised})
            say(f"  step {k}: {'as predicted' if not surprised else 'surprise: ' + surprised}")
            if goal.holds(state):
                run.reached = True
                run.reason = "goal reached"
                say("goal reached")
                return run
            if surprised:
                windfall = goal.distance(state) < goal.distance(step.predicted) - 1e-9
                break
        if not surprised:  # every step went as predicted, yet the goal does not hold
            surprised = "the plan ran as predicted but the goal does not hold"
        helped = windfall and run.windfalls < max_replans
        if helped:
            # The world went the goal's way further than predicted (another object fell
            # too): a new plan is needed, but the model did not let the robot down.
            run.windfalls += 1
        elif run.replans >= max_replans:
            run.reason = f"gave up after {run.replans} replans ({surprised})"
            return run
        else:
            run.replans += 1
        # Behaviours that surprised the robot cost more in the new search: the model would
        # predict the same again, and the robot go round in circles.
        say(f"replanning ({'the surprise helped: no replan counted' if helped else f'replan {run.replans} of at most {max_replans}'}): "
            f"{surprised}")
        plan = planner(state, tuple(failed), held)
        run.plans.append(plan)


class _Imagined:
    """The world as the model predicts it, for :func:`reach_probability`.

    A step's outcome is drawn from the model's distribution; the same behaviour on the same
    object vector gives the same outcome again (the world is not a die: a push that left an
    object where it was will leave it there again), so a rollout is one world the model
    thinks possible. An outcome of a kind the model does not know (the probability it gives
    to none of its categories) does what one of the discarded members most like the object
    did (:meth:`ForwardModel.draw_unknown`), or, where the model kept none, leaves the object
    as it was. Assuming "unknown: nothing happens" made plans look worse than they were:
    at the table many pushes of a discarded kind moved their objects as the kept kinds do.
    """

    def __init__(self, model: ForwardModel, state: np.ndarray, rng: np.random.Generator, whole: bool = False):
        self.model, self.state, self.rng, self.whole = model, state.copy(), rng, whole
        self.fate: dict = {}

    def perceive(self) -> np.ndarray:
        return self.state.copy()

    def _fate(self, f: np.ndarray, b: int, alpha: tuple):
        """(category, effect) this world holds for behaviour ``b`` on entity ``f``: the
        category drawn from the model's distribution, the effect from those the category's
        members most like ``f`` had (:meth:`ForwardModel.draw_effect`). An unknown kind is
        category -1 with an effect a discarded member had (:meth:`ForwardModel.draw_unknown`),
        or None (nothing happens) where there is none to draw. ``whole``: every channel of
        the effect is one member's (``draw_effect(whole=True)``), not only its geometry."""
        key = (f.tobytes(), b, alpha)
        if key not in self.fate:
            classes, proba = self.model.distribution(f, b, alpha)
            edges = np.cumsum(proba)
            r = self.rng.random()
            if edges.size and r < edges[-1]:
                c = int(classes[min(np.searchsorted(edges, r, side="right"), len(classes) - 1)])
                self.fate[key] = (c, self.model.draw_effect(f, b, c, alpha, self.rng, whole=self.whole))
            else:
                effect = self.model.draw_unknown(f, b, alpha, self.rng)
                self.fate[key] = None if effect is None else (-1, effect)
        return self.fate[key]

    def act(self, behavior: str, target: int, alpha: np.ndarray | None = None) -> np.ndarray:
        b = self.model.index(behavior)
        alpha_key = tuple(float(a) for a in (() if alpha is None else alpha))
        if target == SCENE:  # every seen row meets its own fate
            fates = [self._fate(f, b, alpha_key) if self.model.visible(f) else None for f in self.state]
            self.state = self.model.apply(self.state, SCENE, b, [None if x is None else x[0] for x in fates], alpha_key,
                                          effects=[None if x is None else x[1] for x in fates])
            return self.perceive()
        fate = self._fate(self.state[target], b, alpha_key)
        if fate is not None and self.model.visible(self.state[target]):
            self.state = self.model.apply(self.state, target, b, fate[0], alpha_key, effects=fate[1])
        return self.perceive()


def blind_probability(model: ForwardModel, start: np.ndarray, goal: Goal, plan: Plan, *, rollouts: int = 200,
                      seed: int = 0) -> float:
    """P(the goal holds after some step when ``plan`` runs blind, with no monitoring), by the
    model: the fraction of ``rollouts`` imagined worlds (:class:`_Imagined`) where it does.

    Each step's category is drawn from the model's distribution and its effect is the whole
    effect one of the nearest members had (:meth:`ForwardModel.draw_effect` with
    ``whole=True``), every channel, so the next step is judged on a state some member
    really reached. The open-loop walk (:func:`plan.search.success_probability`) judges it
    on the members' mean state instead, which can be a state none of them reached: the
    crane's planner, from its start percept, gave lying cylinders and spheres two-step
    lift plans with a median open-loop probability of 0.7, none of which lifted anything.
    Measured there (258 breadth-first plans on 1000 training episodes; 200 rollouts each),
    the mean predicted success against the rate reached blind in PhysX: open-loop 0.81
    against 0.66, blind draws of the geometry alone 0.76, of whole effects 0.69; Brier
    scores 0.171, 0.155 and 0.134. At the table, where plans are mostly one step and no
    mean state misleads the next step, it does not help (286 plans: open-loop 0.50, blind
    0.56, reached 0.46; Brier 0.144 and 0.147).

    The same ``seed`` gives the same figure; its standard error is at most
    ``0.5 / sqrt(rollouts)``."""
    if goal.holds(start):
        return 1.0
    if not plan.found:
        return 0.0
    rng = np.random.default_rng(seed)
    reached = 0
    with unwatched():
        for _ in range(rollouts):
            world = _Imagined(model, start, rng, whole=True)
            for step in plan.steps:
                if goal.holds(world.act(step.behavior, step.obj, step.alpha)):
                    reached += 1
                    break
    return reached / rollouts


def reach_probability(model: ForwardModel, start: np.ndarray, goal: Goal, plan: Plan, *, max_replans: int = 3,
                      method: str = "best-first", rollouts: int = 100, seed: int = 0, imagined_nodes: int = 1000,
                      budget: int = 4000, **limits) -> float:
    """P(reaching the goal by running ``plan`` the way :func:`execute` does), by the model.

    The open-loop probability (:func:`plan.search.success_probability`) answers for the
    plan run blind; a robot that monitors its steps and replans when one surprises it (up
    to ``max_replans`` times) reaches the goal more often than that. This runs
    :func:`execute` itself, ``rollouts`` times, in worlds drawn from the model
    (:class:`_Imagined`), and returns the fraction that reached the goal: replanning,
    distrust of behaviours that surprised and the replan budget all count as they will
    when the plan runs for real. Outcomes stay put within a rollout (retrying what failed on
    an object that did not move fails again), so it is not the independent-retries
    arithmetic, which would count a failed push as a coin to toss again. The same
    ``seed`` gives the same figure; its standard error is at most ``0.5 / sqrt(rollouts)``.

    Imagined replans search with at most ``imagined_nodes`` expansions (a search that finds
    nothing spends its whole budget, and imagined rollouts meet many hopeless states); a
    replan that would need more counts as failed, so the figure errs low there. Once the
    imagined searches have expanded ``budget`` nodes in all, no new rollout starts (but at
    least 20 run): the figure then rests on fewer rollouts, which bounds its cost.
    """
    return _reach(model, start, goal, plan, max_replans=max_replans, method=method, rollouts=rollouts, seed=seed,
                  imagined_nodes=imagined_nodes, budget=budget, **limits)[0]


@one_blas_thread
def _reach(model: ForwardModel, start: np.ndarray, goal: Goal, plan: Plan, *, max_replans: int, method: str,
           rollouts: int, seed: int, imagined_nodes: int, budget: int, progress: Callable[[int], None] | None = None,
           **limits) -> tuple[float, int]:
    """:func:`reach_probability` and the number of rollouts it ran; ``progress(done)`` hears
    each rollout end (the imagined replans' searches are not reported)."""
    with unwatched():
        return _rollouts(model, start, goal, plan, max_replans=max_replans, method=method, rollouts=rollouts,
                         seed=seed, imagined_nodes=imagined_nodes, budget=budget, progress=progress, **limits)


def _rollouts(model: ForwardModel, start: np.ndarray, goal: Goal, plan: Plan, *, max_replans: int, method: str,
              rollouts: int, seed: int, imagined_nodes: int, budget: int, progress, **limits) -> tuple[float, int]:
    limits = {**limits, "max_nodes": min(limits.get("max_nodes", imagined_nodes), imagined_nodes)}
    if goal.holds(start):
        return 1.0, 0
    if not plan.found:
        return 0.0, 0
    rng = np.random.default_rng(seed)
    plans: dict = {}
    spent = 0

    def planner(state: np.ndarray, avoid: tuple, held: int) -> Plan:
        nonlocal spent
        key = (np.round(state, 2).tobytes(), tuple((np.round(f, 2).tobytes(), b, o, h) for f, b, o, h in avoid), held)
        if key not in plans:
            # an imagined replan is only run, never reported: its open-loop figure is not needed
            plans[key] = search(model, state, goal, method, avoid=avoid, held=held, open_loop=False, **limits)
            spent += plans[key].expanded
        return plans[key]

    reached = done = 0
    while done < rollouts and (spent < budget or done < min(20, rollouts)):
        world = _Imagined(model, start, rng)
        reached += execute(world, model, goal, method=method, max_replans=max_replans, first=plan,
                           planner=planner).reached
        done += 1
        if progress is not None:
            progress(done)
    return reached / done, done


def assess(model: ForwardModel, start: np.ndarray, goal: Goal, plan: Plan, *, max_replans: int = 3,
           method: str = "best-first", rollouts: int = 100, seed: int = 0, imagined_nodes: int = 1000,
           budget: int = 4000, progress: Callable[[int], None] | None = None, **limits) -> Plan:
    """Make ``plan.success_probability`` the chance of reaching the goal with monitoring
    (:func:`reach_probability`), and ``plan.assess_seconds`` the time that took.

    The open-loop figure stays in ``plan.open_loop_probability``; ``limits`` are the
    search limits replanning would use; ``progress(done)`` hears each imagined run end.

    The monitored figure may come out below the open-loop one, and that is no error: the
    two ask different questions of the model. The open-loop walk moves an object by each
    category's *mean* effect, so a goal the mean meets counts that category as reaching it
    every time, while an imagined world draws each effect from one of the nearest members'
    own (:meth:`ForwardModel.draw_effect`), some of which fall short. Measured on a grasp
    model (300 interactions), one power grasp to raise the contact point by 95 % of its
    lifted category's mean rise: open-loop 0.33, the same plan run blind in 400 imagined
    worlds 0.115, monitored 0.26 (27 rollouts; 0.21 on 400). The open-loop walk also takes a
    repeated step on an unchanged object as a fresh draw, where an imagined world keeps its
    outcome (the world is not a die); the monitor leaves a plan at its first surprise,
    where the blind run goes on and may still get there, to replan with searches capped at
    ``imagined_nodes`` (one that would need more counts as failed), and gives up after
    ``max_replans``. And the figure is a mean over as few as 20 rollouts once ``budget``
    is spent (a standard error up to 0.11): on another scene the same goal gave 0.05 on 20
    rollouts and 0.15 on 400, against 0.19 open-loop.
    """
    if plan.open_loop_probability is None:
        plan.open_loop_probability = plan.success_probability
    if plan.found:
        t0 = time.perf_counter()
        plan.success_probability, plan.rollouts = _reach(
            model, start, goal, plan, max_replans=max_replans, method=method, rollouts=rollouts, seed=seed,
            imagined_nodes=imagined_nodes, budget=budget, progress=progress, **limits)
        plan.assess_seconds = time.perf_counter() - t0
    plan.replans_assumed = max_replans
    return plan


def rank_plans(model: ForwardModel, start: np.ndarray, goal: Goal, candidates: int = 1, *, max_replans: int = 3,
               method: str = "best-first", avoid: tuple = (), held: int = -1, rollouts: int = 100, seed: int = 0,
               imagined_nodes: int = 1000, budget: int = 4000, **limits) -> list[Plan]:
    """Plans ranked by their probability of reaching the goal with monitoring, best first.

    The search gives the ``candidates`` most probable behaviour sequences
    (:func:`plan.search.best_plans`; breadth-first chaining gives one); each is assessed
    (:func:`assess`) and they are sorted by success probability, ties by path probability.
    The most probable path is not always the one most likely to work: a plan whose likely
    failure leaves the object where nothing else works ranks below a slightly less probable
    one whose failures can be repaired. Every candidate's assessment draws the same imagined
    worlds (the same ``seed``), so the ranking compares plans, not luck.
    """
    if method == "best-first":
        plans = best_plans(model, start, goal, max(1, candidates), avoid=avoid, held=held, **limits)
    else:
        plans = [search(model, start, goal, method, avoid=avoid, held=held, **limits)]
    found = sum(p.found for p in plans)
    with (phase(f"assessing {found} plan{'s' * (found != 1)} (imagined runs)", found * rollouts) if found
          else nullcontext(lambda done: None)) as tick:
        done = 0  # imagined runs of the plans assessed so far, each counted in full
        for plan in plans:
            assess(model, start, goal, plan, max_replans=max_replans, method=method, rollouts=rollouts, seed=seed,
                   imagined_nodes=imagined_nodes, budget=budget, progress=lambda k, done=done: tick(done + k),
                   **limits)
            if plan.found:
                done += rollouts
                tick(done)  # a budget that ran out ends the plan's share early
    return sorted(plans, key=lambda p: (-p.success_probability, -p.path_probability))


def ranked_planner(model: ForwardModel, goal: Goal, candidates: int, *, max_replans: int = 3,
                   method: str = "best-first", **limits) -> Callable[[np.ndarray, tuple, int], Plan] | None:
    """The planner :func:`execute` replans with when plans are chosen among ``candidates``
    (None, the plain search, for one)."""
    if candidates <= 1:
        return None

    def planner(state: np.ndarray, avoid: tuple, held: int) -> Plan:
        return rank_plans(model, state, goal, candidates, max_replans=max_replans, method=method, avoid=avoid,
                          held=held, **limits)[0]

    return planner
