"""The simulated hand: a driven articulation with two fingers.

What the robot has: a palm carried by a Cartesian gantry (three prismatic joints and a yaw
joint, all position-driven with finite force) and two prismatic fingers that close towards
each other with a limited grip force. The gantry stands in for the thesis's 7-DOF arm: what
matters for affordances is where the hand goes and with what force, and that everything it
does to an object happens through PhysX contacts.

The arm's reach is a disc of radius ``reach`` about the shoulder (the robot's base): a
behaviour aimed beyond it does not start, and every palm target is pulled back into a disc
``reach + palm_slack`` wide (the palm stands back from the point it aims at).

Hand frame: local x is the approach direction (the fingers point along it), local y the
closing direction, local z up. The palm's centre is the hand's reference point.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sapien

__all__ = ["HandConfig", "Hand"]

_Q_Y = np.array([math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)])      # x -> y
_Q_NEG_Y = np.array([math.cos(math.pi / 4), 0.0, 0.0, -math.sin(math.pi / 4)])  # x -> -y
_Q_Z = np.array([math.cos(-math.pi / 4), 0.0, math.sin(-math.pi / 4), 0.0])     # x -> z


def build_gantry(ab) -> "sapien.physx.PhysxArticulationLinkBuilder":
    """A fixed base, prismatic x, y and z joints and a revolute wrist yaw, on an articulation
    builder; returns the wrist's child link (named ``palm``) for the hand to add its shapes
    and fingers to. Joints are named ``gantry-x|y|z`` and ``wrist``."""
    root = ab.create_link_builder()
    root.set_name("base")
    parent = root
    for name, q in (("x", None), ("y", _Q_Y), ("z", _Q_Z)):
        link = ab.create_link_builder(parent)
        link.set_name(f"gantry-{name}")
        link.set_joint_name(f"gantry-{name}")
        qq = np.array([1.0, 0, 0, 0]) if q is None else q
        link.set_joint_properties("prismatic", limits=[[-3.0, 3.0]],
                                  pose_in_parent=sapien.Pose(q=qq), pose_in_child=sapien.Pose(q=qq))
        link.set_mass_and_inertia(2.0, sapien.Pose(), np.array([0.02, 0.02, 0.02]))
        parent = link
    palm = ab.create_link_builder(parent)
    palm.set_name("palm")
    palm.set_joint_name("wrist")
    palm.set_joint_properties("revolute", limits=[[-math.pi, math.pi]],
                              pose_in_parent=sapien.Pose(q=_Q_Z), pose_in_child=sapien.Pose(q=_Q_Z))
    return palm


def clamp_to_disc(target: np.ndarray, centre, radius: float) -> np.ndarray:
    """``target`` with its (x, y) pulled back into the disc of ``radius`` about ``centre``."""
    t = np.array(target, dtype=float)
    d = t[:2] - np.asarray(centre)
    r = float(np.hypot(*d))
    if r > radius:
        t[:2] = np.asarray(centre) + d * (radius / r)
    return t


@dataclass(frozen=True)
class HandConfig:
    """Geometry and strength of the hand (metres, newtons, kilograms)."""

    palm_half: tuple[float, float, float] = (0.025, 0.12, 0.035)
    finger_half: tuple[float, float, float] = (0.08, 0.02, 0.035)
    finger_open: float = 0.13          # finger centre offset from the palm's midline when open
    finger_closed: float = 0.021       # ... when closed on nothing
    grip_force: float = 60.0
    arm_force: float = 400.0
    reach: float = 0.92                # radius of the reachable disc about the shoulder
    palm_slack: float = 0.15           # the palm may stand this much further out
    shoulder: tuple[float, float] = (0.0, 0.0)
    home: tuple[float, float, float] = (-0.05, 0.0, 1.10)
    friction: float = 1.5

    @property
    def finger_reach(self) -> float:
        """How far the fingertips stand ahead of the palm's centre."""
        return self.palm_half[0] + 2 * self.finger_half[0]

    @property
    def finger_centre(self) -> float:
        """Distance from the palm's centre to the middle of the fingers, along the approach."""
        return self.palm_half[0] + self.finger_half[0]


class GantryHand:
    """What every hand on the gantry shares: how it is begun, and its reach (a disc of
    ``config.reach`` about ``config.shoulder``, palm targets pulled into one ``palm_slack``
    wider)."""

    def _begin(self, scene: sapien.Scene, config, density: float):
        """(material, articulation builder, palm link builder with its box) of a new hand."""
        self.config = c = config
        material = sapien.physx.PhysxMaterial(c.friction, c.friction, 0.0)
        ab = scene.create_articulation_builder()
        palm = build_gantry(ab)
        palm.add_box_collision(half_size=c.palm_half, material=material, density=density)
        return material, ab, palm

    def clamp_to_reach(self, target: np.ndarray) -> np.ndarray:
        """Pull a palm target back into the reachable disc."""
        c = self.config
        return clamp_to_disc(target, c.shoulder, c.reach + c.palm_slack)

    def reaches(self, target: np.ndarray) -> bool:
        d = np.asarray(target[:2], dtype=float) - np.asarray(self.config.shoulder)
        return bool(np.hypot(*d) <= self.config.reach + 1e-9)


class Hand(GantryHand):
    """The hand in one SAPIEN scene; ``world`` steps physics while the hand moves."""

    def __init__(self, scene: sapien.Scene, config: HandConfig = HandConfig()):
        c = config
        material, ab, palm = self._begin(scene, config, density=500)
        fingers = []
        for name, q in (("finger-left", _Q_Y), ("finger-right", _Q_NEG_Y)):
            f = ab.create_link_builder(palm)
            f.set_name(name)
            f.set_joint_properties("prismatic", limits=[[c.finger_closed - 0.001, c.finger_open]],
                                   pose_in_parent=sapien.Pose([c.finger_centre, 0, 0], q),
                                   pose_in_child=sapien.Pose(q=q))
            f.add_box_collision(half_size=c.finger_half, material=material, density=500)
            fingers.append(f)
        self.articulation = ab.build(fix_root_link=True)
        self.articulation.set_name("hand")
        self.links = {link.name: link for link in self.articulation.get_links()}
        for link in self.articulation.get_links():
            link.disable_gravity = True
        self.joints = self.articulation.get_active_joints()
        for j in self.joints[:3]:
            j.set_drive_properties(stiffness=4.0e4, damping=1.5e3, force_limit=c.arm_force)
        self.joints[3].set_drive_properties(stiffness=4.0e3, damping=1.5e2, force_limit=300.0)
        for j in self.joints[4:]:
            j.set_drive_properties(stiffness=3.0e3, damping=4.0e2, force_limit=c.grip_force)
        self.body_links = [self.links[n] for n in ("palm", "finger-left", "finger-right")]
        self.grip_links = {"left": [self.links["finger-left"]], "right": [self.links["finger-right"]]}
        self.teleport(np.array(c.home), yaw=0.0, fingers=c.finger_open)

    def mesh_parts(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Each body link's surface (vertices in the link's frame, triangles), for the camera."""
        from afford.sim.objects import box_mesh

        c = self.config
        return {link.name: box_mesh(c.palm_half if link.name == "palm" else c.finger_half) for link in self.body_links}

    # -- state ---------------------------------------------------------------------------
    @property
    def position(self) -> np.ndarray:
        return np.asarray(self.articulation.get_qpos()[:3], dtype=float)

    @property
    def yaw(self) -> float:
        return float(self.articulation.get_qpos()[3])

    @property
    def finger_opening(self) -> float:
        return float(np.mean(self.articulation.get_qpos()[4:]))

    # -- commands (no stepping here: the world steps) -------------------------------------
    def teleport(self, position: np.ndarray, yaw: float, fingers: float) -> None:
        """Place the hand without simulating the way there (only for moves through free space)."""
        q = np.array([*position, yaw, fingers, fingers], dtype=np.float32)
        self.articulation.set_qpos(q)
        self.articulation.set_qvel(np.zeros_like(q))
        self.set_targets(np.asarray(position, dtype=float), yaw, fingers)

    def set_targets(self, position: np.ndarray, yaw: float, fingers: float | None = None,
                    velocity: np.ndarray | None = None) -> None:
        """Drive targets; ``velocity`` feeds the planned palm velocity forward so the hand
        does not lag behind a moving target."""
        vel = np.zeros(3) if velocity is None else velocity
        for j, v, dv in zip(self.joints[:3], position, vel):
            j.set_drive_target(float(v))
            j.set_drive_velocity_target(float(dv))
        self.joints[3].set_drive_target(float(yaw))
        if fingers is not None:
            for j in self.joints[4:]:
                j.set_drive_target(float(fingers))

    def set_fingers(self, opening: float) -> None:
        for j in self.joints[4:]:
            j.set_drive_target(float(opening))
