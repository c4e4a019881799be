"""Behaviours b(alpha): what the hand does to a perceived object (thesis 8.3.2).

Every behaviour takes its target from perception (the object's perceived bounding box, as
the thesis's robot took "the object position computed from the range camera"), never from
the simulator's ground truth, and acts only by moving the hand; what happens to the object
is PhysX's business.

- ``push-forward``: fist (fingers closed); the hand comes down behind the object (on the
  robot's side) and moves away from the robot until the fingertips pass the object's centre.
- ``push-left`` / ``push-right``: open hand, brought to the object's right / left side,
  moving left / right until the palm passes the object's centre.
- ``lift``: open hand at the object's back-right diagonal, at its middle height, moves in
  until the fingers straddle the centre or the palm touches the object, closes the fingers, raises the hand 25 cm. The hand
  then stays where it is, so a lifted object stays in the hand.

Before any behaviour the hand opens (dropping whatever it held) and rises 10 cm. It travels
to above its approach point through free space without simulation (a teleport at a safe
height), then everything from the descent on is simulated. If the approach point lies
If the point the hand is aimed at (the perceived
centre) lies beyond the arm's reach, the arm does not start and the hand stays where it is. After a push
the hand withdraws 5 cm, rises 15 cm and goes home.

Behaviours may take parameters alpha (:class:`Parameter`); these four take none, chapter 9's
``push(alpha)`` will take an approach direction through the same interface.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Callable

import numpy as np

from afford.features.errors import DataError
from afford.features.objects import extents

if TYPE_CHECKING:
    from afford.sim.world import TableWorld

__all__ = ["Parameter", "Behavior", "Execution", "TABLE_BEHAVIORS"]


@dataclass(frozen=True)
class Parameter:
    """One behaviour parameter: a name, its range and unit.

    ``periodic``: an angle whose ends meet (0 and 360 degrees are one direction); learners
    see it as its sine and cosine (``features.encode_parameters``).
    """

    name: str
    low: float
    high: float
    unit: str = ""
    periodic: bool = False

    def to_json(self) -> dict:
        return {"name": self.name, "low": self.low, "high": self.high, "unit": self.unit, "periodic": self.periodic}


@dataclass(frozen=True)
class Execution:
    """What the robot knows about its own execution (not ground truth of the world)."""

    executed: bool                 # the robot carried the behaviour out (the arm was in reach)
    result: int | None = None      # its own reading of the outcome, an index into the scene's results
    reading: dict | None = None    # the sensor values behind ``result`` (odometry, ...), for reports


@dataclass(frozen=True)
class Behavior:
    """A named behaviour: its parameters, what it acts on, and its controller.

    Behaviours are data as far as everything outside ``sim`` is concerned (``to_json`` is
    what artefacts store, and what learners and planners read):

    ``target``
        ``"object"``: the behaviour acts on one perceived object, whose features the
        controller gets (chapters 7-9); ``None``: it acts on nothing in particular (a
        mobile robot moves, and everything it sees may change; chapters 5-6).
    ``parameters``
        alpha, each with its range and whether it is periodic (chapter 9's approach angle).
    """

    name: str
    parameters: tuple[Parameter, ...]
    controller: Callable[..., Execution]
    description: str = ""
    target: str | None = "object"

    def to_json(self) -> dict:
        return {"name": self.name, "parameters": [p.to_json() for p in self.parameters],
                "description": self.description, "target": self.target}

    def __call__(self, world, target: np.ndarray | None, alpha: np.ndarray | None = None) -> Execution:
        alpha = np.zeros(0) if alpha is None else np.asarray(alpha, dtype=float)
        if alpha.shape != (len(self.parameters),):
            raise DataError(f"{self.name} takes {len(self.parameters)} parameter(s), got {alpha.size}")
        return self.controller(world, target, alpha)


# -- motion primitives --------------------------------------------------------------------
def _move(world: "TableWorld", goal: np.ndarray, yaw: float, speed: float, fingers: float | None = None,
          watch: bool = True, guarded: bool = False) -> None:
    """Drive the palm along a straight line to ``goal`` (clamped to reach).

    ``guarded``: stop where the palm first touches an object (the hand's touch sense).
    """
    hand = world.hand
    dt = world.config.timestep
    start = hand.position
    goal = hand.clamp_to_reach(goal)
    n = max(1, math.ceil(np.linalg.norm(goal - start) / (speed * dt)))
    if fingers is not None:
        hand.set_fingers(fingers)
    velocity = (goal - start) / (n * dt)
    for i in range(1, n + 1):
        hand.set_targets(start + (goal - start) * (i / n), yaw, velocity=velocity)
        world.step(1, watch_contacts=watch)
        if guarded and world.palm_touches_object():
            goal = hand.position
            break
    hand.set_targets(goal, yaw)
    world.step(4, watch_contacts=watch)


def _release(world: "TableWorld") -> None:
    """Open the hand where it is and rise: drops a held object."""
    hand = world.hand
    hand.set_fingers(world.config.hand.finger_open)
    world.step(int(0.3 / world.config.timestep), watch_contacts=True)
    _move(world, hand.position + [0, 0, 0.10], hand.yaw, speed=0.5)
    world.holding = False


def _close(world: "TableWorld", seconds: float = 0.7) -> None:
    """Close the fingers on whatever is between them and hold.

    Both fingers get the closed target at once: their drives then saturate at the same grip
    force, so an object is squeezed evenly (a ramped target makes the forces unequal and
    squeezes a ball out like a seed). The drives' damping keeps the closing speed low.
    """
    world.hand.set_fingers(world.config.hand.finger_closed)
    world.step(int(seconds / world.config.timestep), watch_contacts=True)


def _go_home(world: "TableWorld", approach: np.ndarray) -> None:
    """Withdraw 5 cm against the approach direction (rising at once would drag the object
    up by friction and roll it), rise 15 cm, then go home."""
    hand = world.hand
    _move(world, hand.position - 0.05 * approach, hand.yaw, speed=0.5)
    _move(world, hand.position + [0, 0, 0.15], hand.yaw, speed=0.5)
    cfg = world.config.hand
    hand.teleport(np.array(cfg.home), 0.0, cfg.finger_open)


def _approach(world: "TableWorld", start: np.ndarray, aim: np.ndarray, yaw: float, fingers: float) -> bool:
    """Bring the hand above ``start`` through free space, then lower it there.

    The arm goes only if the point it aims the hand at, ``aim`` (the perceived object's
    centre), is within reach: an arm does not start a motion it cannot finish. A start
    beyond reach is pulled back into it.
    """
    hand = world.hand
    if world.holding:
        _release(world)
    if not hand.reaches(aim):
        return False
    start = hand.clamp_to_reach(start)
    safe = max(world.config.table_top + 0.60, hand.position[2])
    hand.teleport(np.array([start[0], start[1], safe]), yaw, fingers)
    _move(world, start, yaw, speed=1.0)
    return True


def _box(target: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Centre and half extents of a perceived object's bounding box."""
    lo, hi = extents(target)
    return (lo + hi) / 2, (hi - lo) / 2


def _push_height(world: "TableWorld") -> float:
    return world.config.table_top + world.config.hand.palm_half[2] + 0.008


# -- the four behaviours of chapter 8 -----------------------------------------------------
def _push_forward(world: "TableWorld", target: np.ndarray, alpha: np.ndarray) -> Execution:
    cfg = world.config.hand
    centre, half = _box(target)
    z = _push_height(world)
    tip = cfg.finger_reach
    start = np.array([centre[0] - half[0] - tip - 0.06, centre[1], z])
    end = np.array([centre[0] + 0.03 - tip, centre[1], z])
    if not _approach(world, start, centre, 0.0, cfg.finger_closed):
        return Execution(False)
    _move(world, end, 0.0, speed=0.5)
    _go_home(world, np.array([1.0, 0.0, 0.0]))
    return Execution(True)


def _lateral(direction: float) -> Callable[["TableWorld", np.ndarray, np.ndarray], Execution]:
    """Push along +y (direction 1, push-left) or -y (direction -1, push-right) with an open hand."""

    def push(world: "TableWorld", target: np.ndarray, alpha: np.ndarray) -> Execution:
        cfg = world.config.hand
        centre, half = _box(target)
        z = _push_height(world)
        yaw = direction * math.pi / 2
        start = np.array([centre[0], centre[1] - direction * (half[1] + cfg.finger_reach + 0.06), z])
        end = np.array([centre[0], centre[1] + direction * (0.03 - cfg.palm_half[0]), z])
        if not _approach(world, start, centre, yaw, cfg.finger_open):
            return Execution(False)
        _move(world, end, yaw, speed=0.5)
        _go_home(world, np.array([0.0, direction, 0.0]))
        return Execution(True)

    return push


def _lift(world: "TableWorld", target: np.ndarray, alpha: np.ndarray) -> Execution:
    cfg = world.config.hand
    centre, half = _box(target)
    yaw = math.pi / 4
    d = np.array([math.cos(yaw), math.sin(yaw), 0.0])
    z = max(centre[2], _push_height(world))
    z = min(z, max(centre[2] + half[2] - 0.02, _push_height(world)))
    reach_out = math.hypot(half[0], half[1]) + cfg.finger_reach + 0.06
    c = np.array([centre[0], centre[1], z])
    # Move in until the fingers straddle the centre, or the palm touches the object first.
    if not _approach(world, c - d * reach_out, centre, yaw, cfg.finger_open):
        return Execution(False)
    _move(world, c - d * cfg.finger_centre, yaw, speed=0.4, guarded=True)
    _close(world)
    _move(world, world.hand.position + [0, 0, 0.25], yaw, speed=0.25)
    world.holding = True
    return Execution(True)


TABLE_BEHAVIORS: tuple[Behavior, ...] = (
    Behavior("push-forward", (), _push_forward, "fist from the robot's side, away from the robot"),
    Behavior("push-left", (), _lateral(1.0), "open hand from the object's right side, to the left"),
    Behavior("push-right", (), _lateral(-1.0), "open hand from the object's left side, to the right"),
    Behavior("lift", (), _lift, "grasp from the back-right diagonal and raise 25 cm"),
)
