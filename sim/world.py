"""One physics world per episode: a table, objects, the hand, the range camera.

``TableWorld`` owns a fresh SAPIEN scene (CPU PhysX, collision shapes only: no render
components, which abort a CPU-only process when the scene is destroyed). It steps physics,
perceives through the range camera, keeps track of the objects it perceives, and reads out
ground truth for reports. Behaviours (``sim.behaviors``) drive the hand through it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
import sapien

from afford.features import RegionOfInterest, object_schema, perceive, track
from afford.features.detect import detect_objects
from afford.features.errors import DataError
from afford.features.interactions import OUTCOMES
from afford.features.objects import centres as object_centres
from afford.sim.camera import CameraConfig, MeshInstance, RangeCamera
from afford.sim.hand import Hand, HandConfig
from afford.sim.objects import ObjectSpec, box_mesh, build_object, object_mesh

__all__ = ["TableConfig", "TableWorld", "ObjectTruth", "outcome_label", "LIFTED"]

#: Ground truth: an object whose bottom ends this far above the table top was lifted.
LIFTED = 0.05


@dataclass(frozen=True)
class TableConfig:
    """The tabletop world of thesis chapter 8 (metres, seconds, kg/m^3)."""

    table_near: float = 0.40          # near edge, in front of the robot
    table_depth: float = 0.70         # frontal
    table_width: float = 1.00         # lateral
    table_top: float = 0.75
    density: float = 300.0
    friction: float = 0.5
    timestep: float = 1 / 60
    settle_max: float = 4.0           # seconds to let objects come to rest after a behaviour
    rolling_damping: float = 0.2      # angular damping of objects (1/s), for rolling resistance
    hand: HandConfig = field(default_factory=HandConfig)
    camera: CameraConfig = field(default_factory=CameraConfig)

    @property
    def table_far(self) -> float:
        return self.table_near + self.table_depth

    def roi(self) -> RegionOfInterest:
        """The volume over the table in which the robot looks for objects."""
        return RegionOfInterest(
            x=(self.table_near, self.table_far),
            y=(-self.table_width / 2, self.table_width / 2),
            z=(self.table_top + 0.008, self.table_top + 0.60),
        )


@dataclass(frozen=True)
class ObjectTruth:
    """What physically is, for evaluation and reports only (never used to learn)."""

    position: np.ndarray     # (3,)
    quaternion: np.ndarray   # (4,) wxyz
    bottom: float            # lowest point, metres
    in_hand: bool


def outcome_label(world: "TableWorld", before: ObjectTruth, after: ObjectTruth, visible: bool) -> int:
    """The first ground-truth label that applies (index into OUTCOMES)."""
    top = world.config.table_top
    if after.position[2] < top:
        return OUTCOMES.index("fell")
    if not visible:
        return OUTCOMES.index("left-view")
    if after.bottom >= top + LIFTED:
        return OUTCOMES.index("lifted")
    moved = float(np.linalg.norm(after.position - before.position))
    turned = 2 * np.degrees(np.arccos(np.clip(abs(float(np.dot(after.quaternion, before.quaternion))), 0, 1)))
    if moved >= 0.02 or turned >= 10.0:
        return OUTCOMES.index("dragged")
    return OUTCOMES.index("no-change")


class TableWorld:
    """A fresh world holding ``objects`` on the table (and the hand at home)."""

    def __init__(self, config: TableConfig, objects: list[ObjectSpec], rng: np.random.Generator,
                 camera: RangeCamera | None = None):
        self.config = c = config
        self.rng = rng
        self.scene = sapien.Scene(systems=[sapien.physx.PhysxCpuSystem()])
        self.scene.set_timestep(c.timestep)
        self.scene.add_ground(0.0, render=False)
        material = sapien.physx.PhysxMaterial(c.friction, c.friction, 0.0)
        half_table = (c.table_depth / 2, c.table_width / 2, c.table_top / 2)
        tb = self.scene.create_actor_builder()
        tb.add_box_collision(half_size=half_table, material=material)
        table_pose = sapien.Pose([c.table_near + c.table_depth / 2, 0.0, c.table_top / 2])
        tb.set_initial_pose(table_pose)
        self.table = tb.build_static(name="table")
        self._table_mesh = (*box_mesh(half_table), np.asarray(table_pose.p), np.array([1.0, 0, 0, 0]))
        self.hand = self._make_hand()
        self._hand_meshes = self.hand.mesh_parts()
        self.specs = list(objects)
        self.bodies = [build_object(self.scene, s, c.table_top, c.density, material) for s in objects]
        self.components = [b.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent) for b in self.bodies]
        for comp in self.components:
            comp.set_max_depenetration_velocity(1.0)
            # PhysX has no rolling resistance; a little angular damping stands in for it,
            # so that rolling objects slow down a little as real ones do.
            comp.set_angular_damping(c.rolling_damping)
        self.camera = camera or RangeCamera(c.camera)
        v, t, p, q = self._table_mesh
        self.camera.set_static([MeshInstance(v, t, p, q)], key=(half_table, tuple(table_pose.p)))
        self.holding = False
        self.contact = False
        self.steps = 0
        held = [i for i, s in enumerate(objects) if s.held]
        if len(held) > 1:
            raise DataError("the hand can hold only one object")
        if held:
            self._start_held(held[0])
        self.known = np.empty((0, len(self.schema)))
        self.identity: list[int] = []

    # -- what a world of another hand or perception replaces ------------------------------------
    schema = object_schema()

    def _make_hand(self):
        return Hand(self.scene, self.config.hand)

    def _features(self, image) -> np.ndarray:
        """The entities in a range image: (k, d) feature vectors."""
        return perceive(image, self.config.roi())

    def _positions(self, features: np.ndarray) -> np.ndarray:
        """Where perceived objects are (k, 3), for tracking and ground truth."""
        return object_centres(features)

    def _track(self, known: np.ndarray, seen: np.ndarray) -> np.ndarray:
        return track(known, seen)

    # -- physics ---------------------------------------------------------------------------
    def step(self, n: int = 1, watch_contacts: bool = False) -> None:
        for _ in range(n):
            self.scene.step()
            if watch_contacts and not self.contact:
                self.contact = self._hand_touches_object()
        self.steps += n

    def _touches_object(self, links) -> bool:
        """Does any of ``links`` press on an object (a contact with a non-zero impulse)?"""
        links = set(links)
        objs = set(self.components)
        for contact in self.scene.get_contacts():
            a, b = contact.bodies
            if (a in links and b in objs) or (b in links and a in objs):
                if any(np.linalg.norm(p.impulse) > 0 for p in contact.points):
                    return True
        return False

    def _hand_touches_object(self) -> bool:
        return self._touches_object(self.hand.body_links)

    def palm_touches_object(self) -> bool:
        """The hand's touch sense: is the palm pressing on an object?"""
        return self._touches_object([self.hand.links["palm"]])

    def settle(self) -> None:
        """Step until every object rests, has fallen below the table, or time runs out."""
        chunk = 6
        for _ in range(int(self.config.settle_max / self.config.timestep) // chunk):
            self.step(chunk)
            moving = False
            for comp in self.components:
                if comp.entity_pose.p[2] < self.config.table_top - 0.1:
                    continue
                if np.linalg.norm(comp.linear_velocity) > 0.01 or np.linalg.norm(comp.angular_velocity) > 0.1:
                    moving = True
                    break
            if not moving:
                return

    def _start_held(self, index: int) -> None:
        """Put object ``index`` in the closed hand, lifted above its table position."""
        c = self.config
        spec = self.specs[index]
        comp = self.components[index]
        lift = 0.20
        centre = np.array([spec.position[0], spec.position[1], c.table_top + spec.height / 2 + lift])
        yaw = math.radians(45.0)
        d = np.array([math.cos(yaw), math.sin(yaw), 0.0])
        comp.set_entity_pose(sapien.Pose(centre, spec.pose(c.table_top).q))
        palm = centre - d * c.hand.finger_centre
        # Fingers just clear of the object's widest horizontal extent, then squeeze.
        width = max(spec.extents[0], spec.extents[1]) / 2
        opening = min(c.hand.finger_open, width + c.hand.finger_half[1] + 0.002)
        self.hand.teleport(palm, yaw, opening)
        self.hand.set_fingers(c.hand.finger_closed)
        comp.set_linear_velocity(np.zeros(3))
        self.step(int(0.5 / c.timestep))
        self.holding = True

    # -- perception ------------------------------------------------------------------------
    def meshes(self) -> list[MeshInstance]:
        """The moving bodies as the camera sees them (the table is the camera's static part)."""
        out = []
        for spec, body in zip(self.specs, self.bodies):
            pose = body.pose
            v, t = object_mesh(spec)
            out.append(MeshInstance(v, t, np.asarray(pose.p), np.asarray(pose.q)))
        for link in self.hand.body_links:
            pose = link.entity_pose
            v, t = self._hand_meshes[link.name]
            out.append(MeshInstance(v, t, np.asarray(pose.p), np.asarray(pose.q), own_body=True))
        return out

    def look(self) -> np.ndarray:
        """Detect the objects in view now: (k, 43) feature vectors."""
        image = self.camera.capture(self.meshes(), self.rng)
        self.last_image = image
        return self._features(image)

    def last_view(self, image=None) -> tuple[np.ndarray, list[tuple[int, int, int, int]]] | None:
        """The last range image (or ``image``, an earlier look's) as (H, W) ranges (inf where
        nothing was hit) and each detected object's pixel box (row0, col0, row1, col1), in the
        order of that look's feature rows; None before the first look. For pictures only:
        detection runs again on the same image."""
        image = getattr(self, "last_image", None) if image is None else image
        if image is None:
            return None
        boxes = []
        for d in detect_objects(image, self.config.roi()):
            (r, c), (h, w) = d.origin, d.mask.shape
            boxes.append((int(r), int(c), int(r + h), int(c + w)))
        return np.asarray(image.ranges), boxes

    def perceive(self) -> np.ndarray:
        """Perceive and keep track of the objects first seen (vanished ones: visibility 0)."""
        seen = self.look()
        if self.known.shape[0] == 0:
            self.known = seen
            self._identify(seen)
        else:
            self.known = self._track(self.known, seen)
        return self.known.copy()

    # -- ground truth ----------------------------------------------------------------------
    def _identify(self, seen: np.ndarray) -> None:
        """Pair each tracked object with the body it is (for ground truth only)."""
        from scipy.optimize import linear_sum_assignment

        if seen.shape[0] == 0 or not self.bodies:
            self.identity = []
            return
        centres = self._positions(seen)[:, :2]
        true = np.array([np.asarray(b.pose.p[:2]) for b in self.bodies])
        cost = np.linalg.norm(centres[:, None, :] - true[None, :, :], axis=2)
        rows, cols = linear_sum_assignment(cost)
        identity = [int(i) for i in cost.argmin(axis=1)]  # a split object: its nearest body
        for r, c in zip(rows, cols):
            identity[r] = int(c)
        self.identity = identity

    def outcomes(self, before: list[ObjectTruth], after: list[ObjectTruth], perceived: np.ndarray) -> list[int]:
        """Each tracked object's ground-truth outcome (an index into ``features.OUTCOMES``)."""
        return [outcome_label(self, a, b, bool(perceived[i, 0])) for i, (a, b) in enumerate(zip(before, after))]

    def tracked_truth(self) -> list[ObjectTruth]:
        """Ground truth in the order of the tracked objects."""
        truth = self.truth()
        return [truth[i] for i in self.identity]

    def truth(self) -> list[ObjectTruth]:
        finger_of = {link: name for name, links in self.hand.grip_links.items() for link in links}
        touching: dict[int, set] = {i: set() for i in range(len(self.components))}
        index = {comp: i for i, comp in enumerate(self.components)}
        for contact in self.scene.get_contacts():
            a, b = contact.bodies
            for x, y in ((a, b), (b, a)):
                if x in index and y in finger_of:
                    touching[index[x]].add(finger_of[y])
        out = []
        for i, comp in enumerate(self.components):
            pose = comp.entity_pose
            lo, _ = comp.compute_global_aabb_tight()
            out.append(ObjectTruth(np.asarray(pose.p, dtype=float), np.asarray(pose.q, dtype=float),
                                   float(lo[2]), len(touching[i]) >= 2))
        return out
