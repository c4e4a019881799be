"""A three-finger hand on a floating base (thesis chapter 9's Gifu hand, in miniature).

What the robot has: a palm carried by the same Cartesian gantry as the chapter-8 hand
(prismatic x, y, z and a driven wrist yaw, ``sim.hand.build_gantry``), and three fingers of
two phalanges each: an index and a middle finger on one side of the palm, one above the
other, and a thumb facing the index on the other side. Every finger joint turns about the
hand's vertical axis, so the fingers close in the horizontal plane the hand approaches in
(thesis 9.3.2: "the robot hand is moved only in horizontal plane above the table").

All joints are PD drives; the base also gets the planned velocity fed forward (without it
the base lags about 5 cm per 1 m/s and knocks objects over, DESIGN.md section 12). Gravity
is off on the hand's links. A finger closes towards a target angle with a limited torque,
so it stops where the object stops it; what is grasped and what slips is PhysX's business.

Hand frame: local x is the approach direction (the fingers point along it), local y the
closing direction (index and middle on +y, thumb on -y), local z up. The palm's centre is
the hand's reference point. A finger's ``opening`` is a fraction: 1 spread wide, 0 closed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import sapien

from afford.sim.hand import _Q_Z, GantryHand

__all__ = ["FingerHandConfig", "FingerHand", "FINGERS", "PRECISION"]

#: Finger names in joint order; each has a proximal and a distal phalanx.
FINGERS = ("index", "middle", "thumb")
#: The fingers a precision grasp closes.
PRECISION = ("index", "thumb")


@dataclass(frozen=True)
class FingerHandConfig:
    """Geometry and strength of the hand (metres, radians, newtons, kilograms)."""

    palm_half: tuple[float, float, float] = (0.02, 0.085, 0.035)
    phalanx: tuple[float, float] = (0.08, 0.065)      # proximal and distal lengths (a large hand's)
    finger_half: float = 0.011                        # half the thickness of a phalanx
    finger_y: float = 0.075                           # fingers' bases either side of the midline
    finger_z: dict | None = None                      # height of each finger's base (None: default)
    spread: float = math.radians(35.0)                # proximal joints when the hand is open
    # Closed targets (proximal, distal). Both grips close to the same angles: a target the
    # fingers cannot reach curls them across the object's face and flings it (measured:
    # 60/60 deg lifted 2 of 27 small objects, 30/40 deg 22; this larger hand lifts
    # objects up to about 16 cm across); what makes a grasp "power" is
    # that all three fingers close with the palm on the object (``sim.grasp``).
    closed: tuple[float, float] = (math.radians(30.0), math.radians(40.0))
    pinch: tuple[float, float] = (math.radians(30.0), math.radians(40.0))
    finger_torque: float = 2.5                        # drive torque limit per finger joint (N m)
    finger_stiffness: float = 20.0
    finger_damping: float = 0.5
    arm_force: float = 400.0
    reach: float = 0.92
    palm_slack: float = 0.15
    shoulder: tuple[float, float] = (0.0, 0.0)
    home: tuple[float, float, float] = (-0.05, 0.0, 1.10)
    friction: float = 1.5
    #: How far ahead of the palm's centre the tips of the closed index and thumb stand. They
    #: close towards each other and stop where they meet, before their targets (which
    #: would cross them over): 13.4-13.8 cm, measured in PhysX and tested. A pinch closes
    #: there; a push aims the fist's front (``fist_front``), not the palm.
    tips_meet: float = 0.1365
    finger_open: float = 1.0                          # the interface the chapter-8 primitives use
    finger_closed: float = 0.0

    def heights(self) -> dict[str, float]:
        return self.finger_z or {"index": 0.012, "middle": -0.02, "thumb": 0.012}

    @property
    def finger_reach(self) -> float:
        """How far the fingertips of the open hand stand ahead of the palm's centre."""
        return self.palm_half[0] + (self.phalanx[0] + self.phalanx[1]) * math.cos(self.spread)

    @property
    def finger_centre(self) -> float:
        """Distance from the palm's centre to the middle of the open fingers, along the approach."""
        return self.palm_half[0] + (self.phalanx[0] + self.phalanx[1]) * math.cos(self.spread) / 2

    def angles(self, opening: float, grip: str = "fist") -> tuple[float, float]:
        """(proximal, distal) joint angles, inwards positive, of a finger opened by ``opening``
        towards a ``grip`` of ``fist`` (every finger curled round) or ``pinch`` (tips meeting ahead)."""
        f = float(np.clip(opening, 0.0, 1.0))
        closed = self.closed if grip == "fist" else self.pinch
        return (f * -self.spread + (1 - f) * closed[0], (1 - f) * closed[1])

    @property
    def pinch_reach(self) -> float:
        """How far ahead of the palm's centre the tips of a closed pinch meet."""
        return self.tips_meet

    @property
    def fist_front(self) -> float:
        """How far ahead of the palm's centre the closed fist's front stands (its fingertips'
        outer face)."""
        return self.tips_meet + self.finger_half


class FingerHand(GantryHand):
    """The hand in one SAPIEN scene; the world steps physics while the hand moves."""

    def __init__(self, scene: sapien.Scene, config: FingerHandConfig = FingerHandConfig()):
        c = config
        material, ab, palm = self._begin(scene, config, density=400)
        heights = c.heights()
        self._sign = {}
        for name in FINGERS:
            side = -1.0 if name == "thumb" else 1.0
            self._sign[name] = -side  # inwards: towards the midline
            parent = palm
            base = sapien.Pose([c.palm_half[0], side * c.finger_y, heights[name]], _Q_Z)
            for k, length in enumerate(c.phalanx):
                link = ab.create_link_builder(parent)
                link.set_name(f"{name}-{k}")
                link.set_joint_name(f"{name}-{k}")
                link.set_joint_properties("revolute", limits=[[-math.pi * 0.6, math.pi * 0.6]],
                                          pose_in_parent=base, pose_in_child=sapien.Pose(q=_Q_Z))
                link.add_box_collision(sapien.Pose([length / 2, 0, 0]), half_size=(length / 2, c.finger_half, c.finger_half),
                                       material=material, density=400)
                parent = link
                base = sapien.Pose([length, 0, 0], _Q_Z)
        self.articulation = ab.build(fix_root_link=True)
        self.articulation.set_name("hand")
        self.links = {link.name: link for link in self.articulation.get_links()}
        for link in self.articulation.get_links():
            link.disable_gravity = True
        joints = {j.name: j for j in self.articulation.get_active_joints()}
        self._order = [j.name for j in self.articulation.get_active_joints()]
        self.base_joints = [joints[n] for n in ("gantry-x", "gantry-y", "gantry-z")]
        self.wrist = joints["wrist"]
        for j in self.base_joints:
            j.set_drive_properties(stiffness=2.0e4, damping=1.0e3, force_limit=c.arm_force)
        self.wrist.set_drive_properties(stiffness=4.0e3, damping=1.5e2, force_limit=300.0)
        self.finger_joints = {name: (joints[f"{name}-0"], joints[f"{name}-1"]) for name in FINGERS}
        for name, pair in self.finger_joints.items():
            # the thumb opposes two fingers: twice their strength, or it is pushed aside and
            # the object squeezed out past it
            strength = 2.0 if name == "thumb" else 1.0
            for j in pair:
                j.set_drive_properties(stiffness=strength * c.finger_stiffness, damping=strength * c.finger_damping,
                                       force_limit=strength * c.finger_torque)
        self.body_links = [self.links["palm"]] + [self.links[f"{n}-{k}"] for n in FINGERS for k in (0, 1)]
        self.grip_links = {n: [self.links[f"{n}-0"], self.links[f"{n}-1"]] for n in FINGERS}
        self.openings = {n: c.finger_open for n in FINGERS}
        self.teleport(np.array(c.home), yaw=0.0, fingers=c.finger_open)

    def mesh_parts(self) -> dict[str, tuple[np.ndarray, np.ndarray]]:
        """Each body link's surface (vertices in the link's frame, triangles), for the camera."""
        from afford.sim.objects import box_mesh

        c = self.config
        out = {"palm": box_mesh(c.palm_half)}
        for n in FINGERS:
            for k, length in enumerate(c.phalanx):
                v, t = box_mesh((length / 2, c.finger_half, c.finger_half))
                out[f"{n}-{k}"] = (v + np.array([length / 2, 0.0, 0.0]), t)
        return out

    # -- state ---------------------------------------------------------------------------
    def _qpos(self) -> dict[str, float]:
        return dict(zip(self._order, np.asarray(self.articulation.get_qpos(), dtype=float)))

    @property
    def position(self) -> np.ndarray:
        q = self._qpos()
        return np.array([q["gantry-x"], q["gantry-y"], q["gantry-z"]])

    @property
    def yaw(self) -> float:
        return float(self._qpos()["wrist"])

    def fingertip(self, name: str) -> np.ndarray:
        """Where a finger's tip is now (world frame)."""
        link = self.links[f"{name}-1"]
        pose = link.entity_pose
        return np.asarray(pose.to_transformation_matrix() @ np.array([self.config.phalanx[1], 0, 0, 1.0]))[:3]

    # -- commands (no stepping here: the world steps) -------------------------------------
    def _finger_q(self, openings: dict[str, float], grip: str = "fist") -> dict[str, float]:
        out = {}
        for name, f in openings.items():
            a, b = self.config.angles(f, grip)
            s = self._sign[name]
            out[f"{name}-0"], out[f"{name}-1"] = s * a, s * b
        return out

    def teleport(self, position: np.ndarray, yaw: float, fingers: float) -> None:
        """Place the hand without simulating the way there (only for moves through free space)."""
        self.openings = {n: float(fingers) for n in FINGERS}
        q = {"gantry-x": position[0], "gantry-y": position[1], "gantry-z": position[2], "wrist": yaw,
             **self._finger_q(self.openings)}
        qpos = np.array([q[n] for n in self._order], dtype=np.float32)
        self.articulation.set_qpos(qpos)
        self.articulation.set_qvel(np.zeros_like(qpos))
        self.set_targets(np.asarray(position, dtype=float), yaw, fingers)

    def set_targets(self, position: np.ndarray, yaw: float, fingers: float | None = None,
                    velocity: np.ndarray | None = None) -> None:
        """Drive targets; ``velocity`` feeds the planned palm velocity forward."""
        vel = np.zeros(3) if velocity is None else velocity
        for j, v, dv in zip(self.base_joints, position, vel):
            j.set_drive_target(float(v))
            j.set_drive_velocity_target(float(dv))
        self.wrist.set_drive_target(float(yaw))
        if fingers is not None:
            self.set_fingers(fingers)

    def set_fingers(self, opening: float, which: tuple[str, ...] = FINGERS, grip: str = "fist") -> None:
        """Drive the named fingers towards ``opening`` (1 open, 0 closed into ``grip``)."""
        for name in which:
            self.openings[name] = float(opening)
        for name, q in self._finger_q({n: self.openings[n] for n in which}, grip).items():
            joint = self.finger_joints[name[:-2]][int(name[-1])]
            joint.set_drive_target(float(q))
