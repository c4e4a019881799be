"""Executing a plan and watching it (thesis 7.6 and 8.6): act, perceive, compare, replan.

The planner talks to the world through the small :class:`World` protocol, which the
simulator implements (``sim.session.SimWorld``); ``plan`` never imports ``sim``. The world
keeps track of which perceived object is which, so a step's prediction is compared with
the perception of the same objects. When a perceived outcome differs from the predicted one
on the goal's channels, the robot replans from what it perceives, up to ``max_replans`` times,
and a behaviour that already surprised it on an object costs more in the new search (the same
prediction would otherwise send it round in circles).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from plan.forward import ForwardModel
from plan.goals import DEFAULT_TOLERANCE, Goal
from plan.search import Plan, search

__all__ = ["World", "Execution", "execute", "mismatch"]


class World(Protocol):
    def perceive(self) -> np.ndarray: ...

    def act(self, behavior: str, target: int, alpha: np.ndarray | None = None) -> np.ndarray: ...


@dataclass
class Execution:
    reached: bool
    plans: list[Plan] = field(default_factory=list)
    executed: list[dict] = field(default_factory=list)  # every step run, with what was perceived
    replans: int = 0
    reason: str = ""

    def to_json(self) -> dict:
        return {"reached": self.reached, "replans": self.replans, "reason": self.reason,
                "executed": self.executed, "plans": [p.to_json() for p in self.plans]}


def mismatch(goal: Goal, predicted: np.ndarray, perceived: np.ndarray, position_slack: float = 0.08) -> str:
    """Why the perceived state differs from the predicted one on the goal's channels ('' if not)."""
    channels = goal.channels
    for i in range(min(predicted.shape[0], perceived.shape[0])):
        if "visibility" in channels or "position" in channels:
            if (predicted[i, 0] >= 0.5) != (perceived[i, 0] >= 0.5):
                return f"object {i} is {'gone' if perceived[i, 0] < 0.5 else 'still there'}, unlike predicted"
        if "position" in channels and perceived[i, 0] >= 0.5:
            gap = float(np.abs(predicted[i, 1:7] - perceived[i, 1:7]).max())
            if gap > position_slack:
                return f"object {i} ended {gap:.2f} m from where it was predicted"
        if "shape" in channels and perceived[i, 0] >= 0.5:
            gap = float(np.abs(predicted[i, 7:] - perceived[i, 7:]).max())
            if gap > 2 * DEFAULT_TOLERANCE["shape"]:
                return f"object {i} looks different from predicted"
    return ""


def execute(world: World, model: ForwardModel, goal: Goal, *, method: str = "best-first", max_replans: int = 3,
            first: Plan | None = None, **limits) -> Execution:
    """Plan (unless ``first`` is given), execute step by step, replan on surprises."""
    state = world.perceive()
    plan = first if first is not None else search(model, state, goal, method, **limits)
    run = Execution(False, [plan])
    failed: list[tuple[np.ndarray, str, int]] = []  # (object seen before, behaviour, object) that surprised
    while True:
        if not plan.found:
            run.reason = f"no plan found ({plan.reason})"
            return run
        if goal.holds(state):
            run.reached = True
            run.reason = "goal reached"
            return run
        surprised = ""
        for step in plan.steps:
            before = state[step.obj].copy()
            state = world.act(step.behavior, step.obj, np.asarray(step.alpha, dtype=float))
            surprised = mismatch(goal, step.predicted, state)
            if surprised:
                failed.append((before, step.behavior, step.obj))
            run.executed.append({**step.to_json(), "as_predicted": not surprised, "note": surprised})
            if goal.holds(state):
                run.reached = True
                run.reason = "goal reached"
                return run
            if surprised:
                break
        if not surprised:  # every step went as predicted, yet the goal does not hold
            surprised = "the plan ran as predicted but the goal does not hold"
        if run.replans >= max_replans:
            run.reason = f"gave up after {run.replans} replans ({surprised})"
            return run
        run.replans += 1
        # Behaviours that surprised the robot cost more in the new search: the model would
        # predict the same again, and the robot go round in circles.
        plan = search(model, state, goal, method, avoid=tuple(failed), **limits)
        run.plans.append(plan)
