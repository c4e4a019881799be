"""The crane world (thesis chapter 7): the mobile robot with a crane, a floor, objects.

What the robot has
    The crane robot of :mod:`sim.robots.crane` (the chapter-5 base, 60 kg with the crane's
    counterweight, a slewing boom and a magnet plate) and the chapter-5 3D scanner on its
    front (720 x 720 rays, min-downscaled to 360 x 360, 3 mm noise, 4 m range).

The world
    A floor (friction 0.5); the robot at the origin heading +x; objects of
    :class:`sim.traverse.Item` (boxes, upright and lying cylinders, spheres, loose or
    fixed) in its frame. One density for every object, 250 kg/m^3 (a 40 cm box weighs
    16 kg, a 20 cm one 2 kg), so mass follows from volume alone: the robot's
    traction-controlled drive (about 35 N) shoves light objects and stalls against heavy
    ones, and the magnet (400 N) holds every object this density makes.

What the robot perceives (:mod:`features.image_objects`)
    Objects are what stands out of a scan of the empty world taken from the same place on
    the robot (its background), segmented and described by the thesis's 44 features. The
    robot tracks them across its behaviours by where it expects each to be: after a move,
    where its odometry says the object went in its new frame; after a lift, the lifted
    object where the crane carries it.

What the behaviours do
    ``move(rotate_deg, 0.40)``: the chapter-5 move (rotate in place, closed loop on the
    gyro, then drive 40 cm). ``lift(target)``: from the target's features the robot
    computes where the object is (the mean range along the direction of its region's
    centre, aimed 4 cm beyond it); if the crane cannot reach there, nothing happens (the
    robot knows its arm). Otherwise the crane turns and runs out over it, lowers the plate
    until the plate presses on something or reaches its lowest point, grips if the magnet
    takes hold (a contact over an area, see :mod:`sim.robots.crane`), raises the plate,
    and turns back to rest. What comes up is what PhysX lifted.

What ground truth is kept (``truth_row``, for reports only)
    The object's shape and size, its pose before and after, whether it hangs from the
    magnet, the robot's true pose after, whether it touched an object, and one outcome
    label, the first that applies: ``lifted``, ``left-view``, ``pushed``, ``no-change``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import sapien
from scipy.optimize import linear_sum_assignment

from afford.features import RangeImage
from afford.features.image_objects import image_object_schema, perceive_against, track_expected
from afford.sim.camera import MeshInstance
from afford.sim.objects import SHAPES, box_mesh, object_mesh
from afford.sim.robots.crane import CraneConfig, CraneRobot, crane_robot_config
from afford.sim.robots.mobile import MobileRobotConfig, Odometry
from afford.sim.scanner import RangeScanner, ScannerConfig
from afford.sim.traverse import TraverseLayout, _plane, build_items

__all__ = ["CraneWorldConfig", "CraneWorld", "CRANE_OUTCOMES", "DRIVE"]

#: Ground-truth outcomes of one behaviour for one object (the first that applies).
CRANE_OUTCOMES = ("lifted", "left-view", "pushed", "no-change")
#: Drive length of the move behaviours, metres (thesis 7.3.2).
DRIVE = 0.40
_SCHEMA = image_object_schema()
_D_AVG, _R_T, _R_B, _C_L, _C_R = (_SCHEMA.index(n) for n in ("d_avg", "r_t", "r_b", "c_l", "c_r"))


@dataclass(frozen=True)
class CraneWorldConfig:
    """Physics and sensing settings of the crane world (metres, seconds, kg/m^3)."""

    timestep: float = 1 / 100
    floor_friction: float = 0.5
    object_friction: float = 0.5
    density: float = 250.0
    rolling_damping: float = 0.2
    robot: MobileRobotConfig = field(default_factory=crane_robot_config)
    crane: CraneConfig = field(default_factory=CraneConfig)
    scanner: ScannerConfig = field(default_factory=ScannerConfig)
    background_margin: float = 0.03
    """A pixel nearer than the empty world's by more than this stands out."""
    aim_beyond: float = 0.04
    """The lift aims this far beyond the object's mean visible point (its near face shows most)."""
    lifted: float = 0.05
    """Ground truth: an object whose bottom ends this far above the floor was lifted."""
    settle_max: float = 2.0


@lru_cache(maxsize=4)
def _scanner(config: ScannerConfig, origin: tuple[float, float, float]) -> RangeScanner:
    return RangeScanner(config, origin)


@lru_cache(maxsize=4)
def _background(config: ScannerConfig, origin: tuple[float, float, float]) -> np.ndarray:
    """The empty world's 360 x 360 ranges, noise-free: the floor only (the crane at rest is
    the robot's own, marked and left out)."""
    scanner = _scanner(config, origin)
    t, _ = scanner.cast([MeshInstance(*_plane(0.0), np.zeros(3), np.array([1.0, 0, 0, 0]))])
    t[t > config.max_range] = np.inf
    k = config.downscale
    if k > 1:
        t = t.reshape(t.shape[0] // k, k, t.shape[1] // k, k).min(axis=(1, 3))
    return t


@dataclass(frozen=True)
class ObjectState:
    """What physically is, for reports only."""

    position: np.ndarray
    quaternion: np.ndarray
    bottom: float
    held: bool


class CraneWorld:
    """A fresh SAPIEN scene: the floor, the layout's objects, the crane robot at the origin."""

    def __init__(self, layout: TraverseLayout, rng: np.random.Generator, config: CraneWorldConfig = CraneWorldConfig()):
        self.layout = layout
        self.rng = rng
        self.config = c = config
        self.scene = sapien.Scene(systems=[sapien.physx.PhysxCpuSystem()])
        self.scene.set_timestep(c.timestep)
        floor = sapien.physx.PhysxMaterial(c.floor_friction, c.floor_friction, 0.0)
        self.scene.add_ground(0.0, render=False, material=floor)
        self.bodies, self.components = build_items(self.scene, layout.items, c.density, c.object_friction,
                                                   c.rolling_damping)
        self.robot = CraneRobot(self.scene, c.robot, c.crane)
        self._robot_links = set(self.robot.articulation.get_links())
        self._objects = {comp: i for i, comp in enumerate(self.components)}
        self.known = np.empty((0, len(_SCHEMA)))
        self.places = np.empty((0, 3))
        self.identity: list[int | None] = []  # tracked object -> body (ground truth only)
        self.contact = False
        self.executed = True
        self.odometry: Odometry | None = None
        self._before = self.truth()
        self._steps = 0

    # -- sensing ---------------------------------------------------------------------------
    @property
    def scanner(self) -> RangeScanner:
        return _scanner(self.config.scanner, self.config.robot.scanner_mount)

    def meshes(self) -> list[MeshInstance]:
        out = []
        for it, body in zip(self.layout.items, self.bodies):
            v, t = object_mesh(it.spec)
            out.append(MeshInstance(v, t, np.asarray(body.pose.p), np.asarray(body.pose.q)))
        out.append(MeshInstance(*_plane(0.0), np.zeros(3), np.array([1.0, 0, 0, 0])))
        pose = self.robot.base.entity_pose
        for centre, half in self.config.robot.body_boxes()[:1]:
            v, t = box_mesh(half)
            out.append(MeshInstance(v + np.asarray(centre), t, np.asarray(pose.p), np.asarray(pose.q), own_body=True))
        plate = self.robot.plate.entity_pose
        hx, hy, hz = self.config.crane.plate_half
        v, t = box_mesh((hx, hy, hz))
        out.append(MeshInstance(v - np.array([0.0, 0.0, hz]), t, np.asarray(plate.p), np.asarray(plate.q), own_body=True))
        return out

    def scan(self) -> RangeImage:
        world_to_robot = self.robot.base.entity_pose.inv().to_transformation_matrix()
        return self.scanner.scan(self.meshes(), self.rng, world_to_robot)

    def place(self, f: np.ndarray) -> np.ndarray:
        """Where an object is (robot frame), as the robot computes it from its features: the
        mean range along the direction of its region's centre."""
        f = np.atleast_2d(f)
        s = self.scanner
        h, w = s.directions.shape[:2]
        rows = np.clip(np.rint(h - 1 - (f[:, _R_T] + f[:, _R_B]) / 2).astype(int), 0, h - 1)
        cols = np.clip(np.rint((f[:, _C_L] + f[:, _C_R]) / 2).astype(int), 0, w - 1)
        return s.origin + f[:, _D_AVG, None] * s.directions[rows, cols]

    def look(self) -> np.ndarray:
        self.last_image = self.scan()
        c = self.config
        return perceive_against(self.last_image, _background(c.scanner, c.robot.scanner_mount), c.background_margin)

    def perceive(self) -> np.ndarray:
        """Perceive, and keep track of the objects first seen (gone ones: visibility 0)."""
        seen = self.look()
        at = self.place(seen) if seen.shape[0] else np.empty((0, 3))
        if self.known.shape[0] == 0 and not self.identity:
            self.known, self.places = seen, at
            self._identify(at)
        else:
            self.known = track_expected(self.known, seen, self.places, at)
            visible = self.known[:, 0] >= 0.5
            if visible.any():
                self.places[visible] = self.place(self.known[visible])
        return self.known.copy()

    def resume(self, other: "CraneWorld") -> None:
        """Know what ``other`` (the same layout, looked at from the same start) has seen."""
        self.known, self.places, self.identity = other.known.copy(), other.places.copy(), list(other.identity)

    def last_view(self, image=None):
        """The last scan's ranges and each tracked object's pixel box (for pictures only)."""
        image = getattr(self, "last_image", None) if image is None else image
        if image is None:
            return None
        h = image.ranges.shape[0]
        boxes = [(int(h - 1 - f[_R_T]), int(f[_C_L]), int(h - f[_R_B]), int(f[_C_R] + 1)) for f in self.known]
        return np.asarray(image.ranges), boxes

    # -- acting ----------------------------------------------------------------------------
    def _step(self) -> None:
        self.scene.step()
        self._steps += 1
        if self._steps % 4 == 0 and not self.contact:
            for contact in self.scene.get_contacts():
                a, b = contact.bodies
                if (a in self._robot_links and b in self._objects) or (b in self._robot_links and a in self._objects):
                    if any(np.any(p.impulse) for p in contact.points):
                        self.contact = True
                        break

    def move(self, rotate_deg: float, drive_m: float = DRIVE) -> Odometry:
        """Rotate in place, drive ahead; every known place moves by the odometry's inverse."""
        self._before = self.truth()
        self.odometry = o = self.robot.move(rotate_deg, drive_m, on_step=self._step)
        th = math.radians(o.heading_change_deg)
        rot = np.array([[math.cos(th), math.sin(th)], [-math.sin(th), math.cos(th)]])
        if self.places.shape[0]:
            held = self._held_index()
            xy = (self.places[:, :2] - [o.dx_m, o.dy_m]) @ rot.T
            self.places[:, :2] = xy
            if held is not None:
                self.places[held] = self._carried_place()
        return o

    def _held_index(self) -> int | None:
        body = self._objects.get(self.robot.held)
        return self.identity.index(body) if body is not None and body in self.identity else None

    def _carried_place(self) -> np.ndarray:
        """Where a held object hangs, robot frame (the crane at rest: the robot knows its arm);
        its height is a middle-sized object's centre, 15 cm below the plate (tracking gates
        at 30 cm, and the place is corrected from the next look)."""
        k = self.config.crane
        slew, boom, drop = k.stow
        th = math.radians(slew)
        plate = k.boom_height - drop - 2 * k.plate_half[2]
        return np.array([k.mast_x + boom * math.cos(th), boom * math.sin(th), plate - 0.15])

    def lift(self, target: np.ndarray) -> bool:
        """Lift the object these features describe (see the module docstring); was it in reach?"""
        self._before = self.truth()
        c = self.config
        robot = self.robot
        p = self.place(target)[0]
        horizontal = p[:2] - robot.config.scanner_mount[:2]
        aim = p[:2] + c.aim_beyond * horizontal / max(np.linalg.norm(horizontal), 1e-9)
        reach = robot.in_reach(float(aim[0]), float(aim[1]))
        if reach is None or robot.held is not None:
            self.executed = False
            return False
        self.executed = True
        slew, boom = reach
        stow = c.crane.stow
        robot.drive_crane((slew, boom, stow[2]), self._step)
        objects = set(self.components)

        def pressing() -> bool:  # on an object, or all but on the floor
            return bool(robot.plate_contacts(objects)) or robot.plate_bottom()[2] < 0.004

        robot.drive_crane((slew, boom, c.crane.drop_limit), self._step, until=pressing, settle=0.0)
        # Press on a little (1 cm further down), reading the contact patch: the magnet grips on an area.
        robot._target[2] = min(robot._target[2] + 0.01, c.crane.drop_limit)
        robot._hold(robot._target)
        patch: dict = {}
        for _ in range(8):
            self._step()
            for body, pts in robot.plate_contacts(objects).items():
                patch.setdefault(body, []).extend(pts)
        for body, pts in patch.items():
            if robot.flat_patch(pts):
                robot.magnetise(body)
                break
        drop = float(robot.crane_joints()[2])
        robot._target[2] = drop
        robot.drive_crane((slew, boom, stow[2]), self._step, settle=0.0)
        robot.drive_crane(stow, self._step)
        if robot.held is not None:  # the coil tells whether iron still closes its circuit
            gap = np.linalg.norm(np.asarray(robot.grip.get_relative_pose().p))
            if gap > 0.02:
                robot.release()
        held = self._held_index()
        if held is not None:
            self.places[held] = self._carried_place()
        return True

    def settle(self) -> None:
        """Step until every loose object rests (or time runs out)."""
        dt = self.config.timestep
        for _ in range(int(self.config.settle_max / dt) // 5):
            for _ in range(5):
                self._step()
            if all(np.linalg.norm(comp.linear_velocity) < 0.01 and np.linalg.norm(comp.angular_velocity) < 0.1
                   for comp in self.components if not comp.kinematic):
                return

    # -- ground truth ----------------------------------------------------------------------
    def truth(self) -> list[ObjectState]:
        out = []
        for comp in self.components:
            pose = comp.entity_pose
            lo, _ = comp.compute_global_aabb_tight()
            out.append(ObjectState(np.asarray(pose.p, dtype=float), np.asarray(pose.q, dtype=float), float(lo[2]),
                                   self.robot.held is comp))
        return out

    def _identify(self, at: np.ndarray) -> None:
        """Pair each perceived object with the body it is (ground truth only)."""
        if at.shape[0] == 0 or not self.bodies:
            self.identity = [None] * at.shape[0]
            return
        true = np.array([np.asarray(b.pose.p[:2]) for b in self.bodies])
        cost = np.linalg.norm(at[:, None, :2] - true[None, :, :], axis=2)
        rows, cols = linear_sum_assignment(cost)
        identity = [int(i) for i in cost.argmin(axis=1)]  # a split object: its nearest body
        for r, col in zip(rows, cols):
            identity[r] = int(col)
        self.identity = identity

    def tracked_truth(self) -> list[ObjectState]:
        truth = self.truth()
        return [truth[i] if i is not None else None for i in self.identity]

    def outcomes(self, before: list, after: list, perceived: np.ndarray) -> list[int]:
        """The first ground-truth label that applies to each tracked object (CRANE_OUTCOMES)."""
        out = []
        for i, (a, b) in enumerate(zip(before, after)):
            if a is None or b is None:
                out.append(CRANE_OUTCOMES.index("no-change"))
            elif b.held and b.bottom >= self.config.lifted:
                out.append(CRANE_OUTCOMES.index("lifted"))
            elif perceived[i, 0] < 0.5:
                out.append(CRANE_OUTCOMES.index("left-view"))
            elif np.linalg.norm(b.position[:2] - a.position[:2]) >= 0.03:
                out.append(CRANE_OUTCOMES.index("pushed"))
            else:
                out.append(CRANE_OUTCOMES.index("no-change"))
        return out

    def truth_row(self) -> dict:
        """Ground truth of the last behaviour for object 0 (the one an exploration episode has)."""
        it = self.layout.items[0] if self.layout.items else None
        a, b = self._before[0] if self._before else None, self.truth()[0] if self.components else None
        pose = self.robot.pose()
        size = np.full(3, np.nan)
        if it is not None:
            size[: len(it.size)] = it.size
        row = {
            "shape": np.int8(SHAPES.index(it.shape) if it else -1),
            "size": size.astype(np.float32),
            "pose_before": np.concatenate([a.position, a.quaternion]).astype(np.float32) if a else np.full(7, np.nan, np.float32),
            "pose_after": np.concatenate([b.position, b.quaternion]).astype(np.float32) if b else np.full(7, np.nan, np.float32),
            "held_after": bool(b.held) if b else False,
            "robot_after": np.array([pose.x, pose.y, pose.yaw], dtype=np.float32),
            "reachable": bool(self.executed),
            "contact": bool(self.contact),
        }
        return row
