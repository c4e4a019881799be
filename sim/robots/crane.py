"""The chapter-7 robot: the mobile robot with a crane arm and a magnetic gripper.

What the robot has
    The six-wheeled base of :mod:`sim.robots.mobile` carrying a slewing crane. The crane's
    mast stands on the body; at its top a boom turns about the vertical (``crane-slew``,
    +-80 deg), runs in and out (``crane-boom``, 25-60 cm from the mast) and lowers a
    hoist (``crane-hoist``) whose end is a magnet plate, 12 x 12 cm. Every joint is a PD
    position drive with velocity feed-forward; the crane's links carry no weight of their
    own (gravity off, as a real crane's brakes hold it), but what hangs from the magnet
    does, and it can tip the robot: the body carries a counterweight behind its centre
    (``com_x``), and the robot weighs 60 kg with it (at 45 kg a 16 kg box at the boom's end
    tipped it 40 deg: measured).

The magnet
    An electromagnet pulls hard on iron it lies flat against and hardly at all on a single
    point or a line of contact. So the magnet grips only when the plate presses on a
    surface over an area: while the plate is being lowered the robot reads the plate's
    contacts (PhysX contact points with non-zero impulse) and grips when they span the
    plate's plane in two directions (their smaller spread is at least
    :attr:`CraneConfig.patch_spread`). A box's or upright cylinder's top gives a patch; a
    sphere gives a point and a lying cylinder a line, so they are never gripped. (The plate
    hangs stiffly and first presses on one edge; the patch counts the points PhysX reports
    within :attr:`CraneConfig.gap` of the plate, as a magnet's field reaches across a small
    air gap.) Nothing
    reads what the object is. The grip is a PhysX drive between the plate and the object,
    made at the pose they touch in, whose force is limited to the magnet's pull
    (:attr:`CraneConfig.pull`): an object heavier than that stays on the floor.

What the robot knows of its crane (its own senses)
    The joints' positions, and whether the magnet holds something (its coil's current
    drops when the circuit closes through iron: here, whether the grip was made).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sapien

from afford.sim.robots.mobile import MobileRobot, MobileRobotConfig

__all__ = ["CraneConfig", "CraneRobot", "CRANE_JOINTS", "crane_robot_config"]

CRANE_JOINTS = ("crane-slew", "crane-boom", "crane-hoist")

_X_TO_Z = np.array([math.cos(-math.pi / 4), 0.0, math.sin(-math.pi / 4), 0.0])   # joint x -> up
_X_TO_DOWN = np.array([math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0])  # joint x -> down


def crane_robot_config() -> MobileRobotConfig:
    """The base under the crane: heavier, its counterweight behind the centre, and more
    torque to turn in place under that weight."""
    return MobileRobotConfig(mass=60.0, com_x=-0.12, turn_torque=10.0)


@dataclass(frozen=True)
class CraneConfig:
    """Geometry, drives and magnet of the crane (metres, degrees, N, s)."""

    mast_x: float = 0.05
    """The slewing axis, ahead of the body's centre."""
    boom_height: float = 1.10
    """Height of the boom (and the hoist's top) above the floor."""
    slew_limit: float = 80.0
    reach: tuple[float, float] = (0.25, 0.60)
    """How far the boom runs out from the mast (the magnet's horizontal distance from it)."""
    drop_limit: float = 1.00
    """How far the hoist lowers the plate below the boom."""
    stow: tuple[float, float, float] = (0.0, 0.40, 0.12)
    """Slew, boom and drop of the crane at rest (and while it carries what it lifted)."""
    plate_half: tuple[float, float, float] = (0.06, 0.06, 0.01)
    link_mass: float = 1.0
    stiffness: float = 2.0e4
    damping: float = 1.0e3
    force_limit: float = 2.0e3
    speed: float = 0.35
    """Boom and hoist speed, m/s."""
    slew_rate: float = 90.0
    """deg/s."""
    pull: float = 400.0
    """The magnet's holding force, N."""
    gap: float = 0.002
    """A surface this close to the plate (m) is held by the magnet's field (the plate, stiffly
    hung, never lies perfectly flat: it presses on one edge first)."""
    patch_spread: float = 0.025
    """The plate's contacts must spread at least this far (m, the smaller standard deviation
    across the plate) for the magnet to grip: an area, not a point or a line. Measured: a
    box's or upright cylinder's top under the plate spreads 4-6 cm both ways; a lying
    cylinder's top facet (its hull has 32 sides, 2-4 cm wide here) 0.8-1.5 cm across; a
    sphere is one point."""


class CraneRobot(MobileRobot):
    """The mobile robot with its crane, in one SAPIEN scene (see the module docstring)."""

    def __init__(self, scene: sapien.Scene, config: MobileRobotConfig | None = None,
                 crane: CraneConfig = CraneConfig(), **pose):
        self.crane = crane
        super().__init__(scene, config or crane_robot_config(), **pose)
        by_name = {j.name: j for j in self.articulation.get_active_joints()}
        self.joints = [by_name[n] for n in CRANE_JOINTS]
        order = [j.name for j in self.articulation.get_active_joints()]
        self._crane_q = np.array([order.index(n) for n in CRANE_JOINTS])
        k = crane
        for j in self.joints:
            j.set_drive_properties(stiffness=k.stiffness, damping=k.damping, force_limit=k.force_limit)
        self.plate = self.links["crane-hoist"]
        for name in CRANE_JOINTS:
            self.links[name].disable_gravity = True
        self.grip: sapien.physx.PhysxDriveComponent | None = None
        self.held = None
        q = np.asarray(self.articulation.get_qpos(), dtype=float)
        q[self._crane_q] = self._joint_values(k.stow)
        self.articulation.set_qpos(q)
        self._target = np.array(self._joint_values(k.stow))
        self._hold(self._target)

    # -- building -------------------------------------------------------------------------
    def _add_links(self, builder, base) -> None:
        k = self.crane
        slew = builder.create_link_builder(base)
        slew.set_name("crane-slew")
        slew.set_joint_name("crane-slew")
        lim = math.radians(k.slew_limit)
        slew.set_joint_properties("revolute", limits=[[-lim, lim]],
                                  pose_in_parent=sapien.Pose([k.mast_x, 0.0, k.boom_height], _X_TO_Z),
                                  pose_in_child=sapien.Pose(q=_X_TO_Z))
        boom = builder.create_link_builder(slew)
        boom.set_name("crane-boom")
        boom.set_joint_name("crane-boom")
        boom.set_joint_properties("prismatic", limits=[list(k.reach)], pose_in_parent=sapien.Pose(),
                                  pose_in_child=sapien.Pose())
        hoist = builder.create_link_builder(boom)
        hoist.set_name("crane-hoist")
        hoist.set_joint_name("crane-hoist")
        hoist.set_joint_properties("prismatic", limits=[[0.0, k.drop_limit]], pose_in_parent=sapien.Pose(q=_X_TO_DOWN),
                                   pose_in_child=sapien.Pose(q=_X_TO_DOWN))
        hx, hy, hz = k.plate_half
        hoist.add_box_collision(sapien.Pose([0.0, 0.0, -hz]), half_size=[hx, hy, hz])
        inertia = np.full(3, k.link_mass * 0.01)
        for link in (slew, boom, hoist):
            link.set_mass_and_inertia(k.link_mass, sapien.Pose(), inertia)

    # -- the crane's own senses -----------------------------------------------------------
    def crane_joints(self) -> np.ndarray:
        """Slew (rad), boom (m) and drop (m), as the joints read."""
        return np.asarray(self.articulation.get_qpos(), dtype=float)[self._crane_q]

    @staticmethod
    def _joint_values(pose: tuple[float, float, float]) -> list[float]:
        slew, boom, drop = pose
        return [math.radians(slew), float(boom), float(drop)]

    def plate_bottom(self) -> np.ndarray:
        """The plate's underside centre in the world frame."""
        return np.asarray(self.plate.entity_pose.p, dtype=float) - np.array([0.0, 0.0, 2 * self.crane.plate_half[2]])

    def in_reach(self, x: float, y: float) -> tuple[float, float] | None:
        """Slew (deg) and boom that put the plate over ``(x, y)`` (robot frame), or None if
        the crane cannot reach there."""
        k = self.crane
        dx = x - k.mast_x
        r = math.hypot(dx, y)
        slew = math.degrees(math.atan2(y, dx))
        if not (k.reach[0] <= r <= k.reach[1]) or abs(slew) > k.slew_limit:
            return None
        return slew, r

    # -- motion ---------------------------------------------------------------------------
    def _hold(self, target: np.ndarray, velocity: np.ndarray | None = None) -> None:
        v = np.zeros(3) if velocity is None else velocity
        for j, q, dq in zip(self.joints, target, v):
            j.set_drive_target(float(q))
            j.set_drive_velocity_target(float(dq))

    def drive_crane(self, goal: tuple[float, float, float], step, until=None, settle: float = 0.2) -> bool:
        """Move the crane to ``goal`` (slew deg, boom m, drop m) at its speeds, calling
        ``step()`` once per physics step; stop early when ``until()`` is true (returns True then)."""
        k = self.crane
        dt = self.scene.timestep
        start = self._target.copy()
        end = np.array(self._joint_values(goal))
        rates = np.array([math.radians(k.slew_rate), k.speed, k.speed])
        n = max(1, int(math.ceil(float(np.max(np.abs(end - start) / rates)) / dt)))
        v = (end - start) / (n * dt)
        for i in range(1, n + 1):
            self._target = start + (end - start) * i / n
            self._hold(self._target, v)
            step()
            if until is not None and until():
                self._target = self.crane_joints()
                self._hold(self._target)
                return True
        self._hold(self._target)
        for _ in range(int(round(settle / dt))):
            step()
        return False

    # -- the magnet -----------------------------------------------------------------------
    def plate_contacts(self, bodies) -> dict:
        """Where the plate lies against each of ``bodies`` it presses on (a contact with a non-zero
        impulse): the contact points (world frame) within :attr:`CraneConfig.gap` of the plate."""
        out: dict = {}
        for contact in self.scene.get_contacts():
            a, b = contact.bodies
            other = b if a is self.plate else a if b is self.plate else None
            if other is None or other not in bodies:
                continue
            if not any(np.any(p.impulse) for p in contact.points):
                continue  # within PhysX's contact offset but not pressing
            pts = [np.asarray(p.position, dtype=float) for p in contact.points if p.separation <= self.crane.gap]
            out.setdefault(other, []).extend(pts)
        return out

    def flat_patch(self, points: list[np.ndarray]) -> bool:
        """Do these contact points span the plate's plane in two directions (an area)?"""
        if len(points) < 3:
            return False
        p = np.asarray(points)[:, :2]
        p = p - p.mean(axis=0)
        s = np.linalg.svd(p, compute_uv=False) / math.sqrt(len(p))
        return bool(s[-1] >= self.crane.patch_spread)

    def magnetise(self, body) -> None:
        """Grip ``body`` where it lies against the plate (a drive limited to the magnet's pull)."""
        k = self.crane
        pose_plate = self.plate.entity_pose
        pose_body = body.entity_pose
        relative = pose_body.inv() * pose_plate
        self.grip = self.scene.create_drive(self.plate, sapien.Pose(), body, relative)
        for axis in ("x", "y", "z"):
            getattr(self.grip, f"set_drive_property_{axis}")(1.0e5, 2.0e3, k.pull)
        self.grip.set_drive_property_slerp(1.0e3, 50.0, k.pull * 0.2)
        self.grip.set_drive_target(sapien.Pose())
        self.held = body

    def release(self) -> None:
        if self.grip is not None:
            self.grip.disable()
        self.grip = None
        self.held = None
