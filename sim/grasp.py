"""The grasp world (thesis chapter 9): chapter 8's table, a three-finger hand, parametric behaviours.

What the robot has
    The hand of :mod:`sim.robots.fingers` (thumb, index and middle finger of two phalanges
    each, on the chapter-8 gantry with a driven wrist yaw), touch over the whole hand (a
    PhysX contact of non-zero impulse between any of its links and an object), and a range
    camera across the table, facing the robot (thesis 9.3.4).

What the robot perceives (:mod:`features.contact_point`)
    Each object's 25 contact-point features. Objects are tracked across behaviours by their
    contact points; then ``touch`` is 1 for the tracked object the hand presses on (the one
    whose contact point lies nearest the hand's contacts, within 25 cm: the robot knows
    where on its hand it feels a touch, not what it touches), 0 for the rest and for
    vanished ones.

What the behaviours do (all aimed at the perceived contact point, CP)
    Every behaviour takes one parameter, the angle alpha in degrees; ``d(alpha)`` is the
    horizontal direction (cos alpha, sin alpha): 0 is straight away from the robot, +90 to
    its left. The hand works at the grasp height, 4.5 cm below the CP but clear of the table.

    - ``open-hand(alpha)``, alpha in [-90, 90]: turn the wrist by alpha and open every finger
      (a held object drops).
    - ``move-hand(alpha)``, alpha in [0, 360): move the hand 10 cm along d(alpha) where it is,
      fingers as they are (a held object goes with it).
    - ``push-object(alpha)``, alpha in [-90, 90]: a fist comes along d(alpha) to the CP and
      goes on 10 cm, then the hand goes home.
    - ``power-grasp(alpha)``: the open hand comes along d(alpha) until the palm touches the
      object or reaches the CP; every finger closes into a fist; the hand rises 25 cm.
    - ``precision-grasp(alpha)``: the open hand comes along d(alpha) until the point where
      the thumb's and index's tips meet reaches 5.5 cm past the CP (or the palm touches);
      only those two close, into a pinch; the hand rises 25 cm.

    A behaviour whose CP lies beyond the arm's reach does not start. The grasp and push
    behaviours first open the hand where it is and rise (dropping what it held); open-hand
    and move-hand act from where the hand is, so that after a grasp they act on the held
    object (thesis 9.3.3: "in case there is an object in robot's hand, the robot executes a
    different set of behaviors").

What ground truth is kept (for reports only)
    The first that applies: ``fell`` (off the table), ``left-view``, ``lifted`` (the bottom
    5 cm or more above the table), ``slipping`` (not lifted, yet two fingers or more
    still press on it after the behaviour: chapter 9's unstable lift), ``dragged`` and ``no-change``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from afford.features.contact_point import contact_point_schema, cp_positions, perceive_contact_points
from afford.features.objects import match
from afford.sim.behaviors import Behavior, Execution, Parameter, _approach, _go_home, _move
from afford.sim.camera import CameraConfig
from afford.sim.robots.fingers import FINGERS, PRECISION, FingerHand, FingerHandConfig
from afford.sim.world import LIFTED, ObjectTruth, TableConfig, TableWorld

__all__ = ["GraspConfig", "GraspWorld", "GRASP_BEHAVIORS", "GRASP_OUTCOMES"]

#: Ground-truth outcomes, the first that applies.
GRASP_OUTCOMES = ("fell", "left-view", "lifted", "slipping", "dragged", "no-change")

#: The hand works this far below the contact point (metres): the CP is on the visible
#: surface's edge nearest the robot, at the top of a box or a cylinder.
GRASP_BELOW = 0.045

#: How far past the CP a push takes the fist's front (metres; thesis 9.3.2).
PUSH = 0.10

#: Where a precision grasp's approach ends: the thumb's and index's tips meet this far past
#: the CP (metres). Earlier sessions wrote 3 cm against a pinch point computed as if the
#: tips could cross; where they really meet (``FingerHandConfig.tips_meet``) puts it here,
#: which is what every measurement of this hand so far was made with.
PINCH_PAST = 0.055

#: Where a power grasp's approach ends: the palm's face this far past the CP (metres).
POWER_PAST = 0.01

_SCHEMA = contact_point_schema()
_VISIBLE = _SCHEMA.visibility_index
_TOUCH = _SCHEMA.index("touch")


def _camera_across() -> CameraConfig:
    """The range camera across the table from the robot, looking back at it from above."""
    return CameraConfig(position=(2.05, 0.0, 1.55), look_at=(0.75, 0.0, 0.78))


@dataclass(frozen=True)
class GraspConfig(TableConfig):
    """Chapter 8's table with the three-finger hand and the camera across the table."""

    timestep: float = 1 / 120
    hand: FingerHandConfig = field(default_factory=FingerHandConfig)
    camera: CameraConfig = field(default_factory=_camera_across)
    touch_gate: float = 0.25          # a touch belongs to the object whose CP is nearest, within this


class GraspWorld(TableWorld):
    """A fresh world with the three-finger hand; perceives contact-point features."""

    schema = _SCHEMA

    def _make_hand(self):
        return FingerHand(self.scene, self.config.hand)

    def _touch_points(self) -> np.ndarray:
        """Where the hand presses on something movable now (the robot's tactile reading)."""
        links = set(self.hand.body_links)
        movable = set(self.components)
        points = []
        for contact in self.scene.get_contacts():
            a, b = contact.bodies
            if (a in links and b in movable) or (b in links and a in movable):
                points += [np.asarray(p.position) for p in contact.points if np.linalg.norm(p.impulse) > 0]
        return np.asarray(points).reshape(-1, 3)

    def _with_touch(self, f: np.ndarray) -> np.ndarray:
        f = f.copy()
        f[:, _TOUCH] = 0.0
        touch = self._touch_points()
        seen = np.flatnonzero(f[:, _VISIBLE] > 0.5)
        if touch.shape[0] and seen.size:
            d = np.linalg.norm(cp_positions(f[seen])[:, None, :] - touch[None, :, :], axis=2).min(axis=1)
            if d.min() <= self.config.touch_gate:
                f[seen[int(np.argmin(d))], _TOUCH] = 1.0
        return f

    def _features(self, image) -> np.ndarray:
        f, _ = perceive_contact_points(image, self.config.roi(), self.config.hand.shoulder)
        return f

    def perceive(self) -> np.ndarray:
        """Perceive, track, then feel: the touch goes to the tracked object nearest the
        hand's contacts (fingers may split a held object into two detections; the touch
        belongs to the one the robot tracks)."""
        super().perceive()
        self.known = self._with_touch(self.known)
        return self.known.copy()

    def _positions(self, features: np.ndarray) -> np.ndarray:
        return cp_positions(features)

    def _track(self, known: np.ndarray, seen: np.ndarray) -> np.ndarray:
        return match(known, seen, cp_positions(known), cp_positions(seen), 0.35, _VISIBLE)

    def outcomes(self, before: list[ObjectTruth], after: list[ObjectTruth], perceived: np.ndarray) -> list[int]:
        top = self.config.table_top
        out = []
        for i, (a, b) in enumerate(zip(before, after)):
            if b.position[2] < top:
                name = "fell"
            elif not perceived[i, _VISIBLE]:
                name = "left-view"
            elif b.bottom >= top + LIFTED:
                name = "lifted"
            elif b.in_hand:
                name = "slipping"
            else:
                moved = float(np.linalg.norm(b.position - a.position))
                turned = 2 * np.degrees(np.arccos(np.clip(abs(float(np.dot(b.quaternion, a.quaternion))), 0, 1)))
                name = "dragged" if moved >= 0.02 or turned >= 10.0 else "no-change"
            out.append(GRASP_OUTCOMES.index(name))
        return out


# -- the five behaviours of chapter 9 ------------------------------------------------------
def _direction(alpha_deg: float) -> np.ndarray:
    a = math.radians(alpha_deg)
    return np.array([math.cos(a), math.sin(a), 0.0])


def _cp(target: np.ndarray) -> np.ndarray:
    return cp_positions(target).astype(float)


def _grasp_height(world: GraspWorld, cp: np.ndarray) -> float:
    low = world.config.table_top + world.config.hand.palm_half[2] + 0.006
    return float(max(cp[2] - GRASP_BELOW, low))


def _lateral_extent(target: np.ndarray) -> float:
    """How far the object reaches sideways from its CP, as the robot sees it (the left and
    right border distances): the approach starts beyond it."""
    return float(max(target[_SCHEMA.index("border_left")], target[_SCHEMA.index("border_right")]))


def _start_of(world: GraspWorld, target: np.ndarray, d: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(the CP at the grasp height, where the approach along ``d`` starts)."""
    cfg = world.config.hand
    cp = _cp(target)
    at = np.array([cp[0], cp[1], _grasp_height(world, cp)])
    return at, at - d * (cfg.finger_reach + 0.06 + 0.5 * _lateral_extent(target))


def _open_hand(world: GraspWorld, target: np.ndarray, alpha: np.ndarray) -> Execution:
    hand = world.hand
    yaw0, yaw1 = hand.yaw, hand.yaw + math.radians(float(alpha[0]))
    n = max(1, int(0.5 / world.config.timestep))
    for i in range(1, n + 1):
        hand.set_targets(hand.position, yaw0 + (yaw1 - yaw0) * i / n)
        world.step(1, watch_contacts=True)
    hand.set_fingers(world.config.hand.finger_open)
    world.step(int(0.5 / world.config.timestep), watch_contacts=True)
    world.holding = False
    return Execution(True)


def _move_hand(world: GraspWorld, target: np.ndarray, alpha: np.ndarray) -> Execution:
    hand = world.hand
    goal = hand.position + 0.10 * _direction(float(alpha[0]))
    _move(world, goal, hand.yaw, speed=0.2)
    return Execution(True)


def _push_object(world: GraspWorld, target: np.ndarray, alpha: np.ndarray) -> Execution:
    cfg = world.config.hand
    d = _direction(float(alpha[0]))
    at, start = _start_of(world, target, d)
    at[2] = start[2] = world.config.table_top + cfg.palm_half[2] + 0.008
    if not _approach(world, start, at, float(math.radians(alpha[0])), cfg.finger_closed):
        return Execution(False)
    # the fist's front (the closed fingers, not the palm) goes 10 cm past the CP
    _move(world, at + d * (PUSH - cfg.fist_front), world.hand.yaw, speed=0.4)
    _go_home(world, d)
    return Execution(True)


def _grasp(fingers: tuple[str, ...], grip: str):
    def grasp(world: GraspWorld, target: np.ndarray, alpha: np.ndarray) -> Execution:
        cfg = world.config.hand
        hand = world.hand
        d = _direction(float(alpha[0]))
        yaw = math.radians(float(alpha[0]))
        at, start = _start_of(world, target, d)
        if not _approach(world, start, at, yaw, cfg.finger_open):
            return Execution(False)
        stand = cfg.palm_half[0] - POWER_PAST if grip == "fist" else cfg.pinch_reach - PINCH_PAST
        _move(world, at - d * stand, yaw, speed=0.3, guarded=True)
        hand.set_fingers(cfg.finger_closed, fingers, grip)
        world.step(int(0.7 / world.config.timestep), watch_contacts=True)
        _move(world, hand.position + [0, 0, 0.25], yaw, speed=0.25)
        world.holding = True
        return Execution(True)

    return grasp


_APPROACH = Parameter("alpha", -90.0, 90.0, "deg", periodic=True)

GRASP_BEHAVIORS: tuple[Behavior, ...] = (
    Behavior("open-hand", (_APPROACH,), _open_hand, "turn the wrist by alpha and open the hand"),
    Behavior("move-hand", (Parameter("alpha", 0.0, 360.0, "deg", periodic=True),), _move_hand,
             "move the hand 10 cm in direction alpha"),
    Behavior("push-object", (_APPROACH,), _push_object, "a fist from direction alpha, 10 cm past the contact point"),
    Behavior("power-grasp", (_APPROACH,), _grasp(FINGERS, "fist"),
             "open hand from direction alpha to the contact point, every finger closes, lift 25 cm"),
    Behavior("precision-grasp", (_APPROACH,), _grasp(PRECISION, "pinch"),
             "thumb and index pinch at the contact point from direction alpha, lift 25 cm"),
)
