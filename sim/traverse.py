"""Traverse worlds (thesis chapter 5): a mobile robot, a floor, and what lies in its way.

What the robot has
    The six-wheeled skid-steer base of ``sim.robots.mobile`` (45 x 33 x 47 cm, 22 kg,
    traction-controlled drive, wheel encoders and a gyro) and, on top at its front, the
    3D range scanner of ``sim.scanner`` (720 x 720 rays over 180 deg x +-82.8 deg, 3 mm
    noise, down-scaled to 360 x 360 by the nearest of each 2 x 2 block, 4 m range).

The world
    A floor (friction 0.5) in front of the robot, which stands at the origin heading +x.
    A layout (:class:`TraverseLayout`) adds, in the robot's start frame:

    * objects (:class:`Item`): boxes, upright cylinders, lying cylinders and spheres,
      resting on the floor and free to move (``fixed = false``), or fixed where they are
      (``fixed = true``; ``z`` lifts a fixed box's bottom off the floor: a hanging box);
    * ramps (:class:`Ramp`): static wedges;
    * a gap (:class:`Gap`): a trench across the floor, 50 cm deep. The floor is then two
      static slabs with the space between them and the trench's bottom below (no ground
      plane: a ground plane would fill the gap).

    Masses: one density for every object, 2000 kg/m^3 (stone, dense plastic), so that mass
    follows from volume and nothing is made heavy or light by its shape's name. What happens
    then is geometry and friction. The robot's traction-controlled drive pushes with about
    35 N, and anything resting on the floor (friction 0.5) that weighs more than about 7 kg
    does not slide for it: a box of 20 cm (16 kg) or an upright cylinder of 20 x 30 cm
    (19 kg) blocks it, a 15 cm one (7 kg or less) is shoved along, a tall thin cylinder may
    topple. A sphere rolls away whatever it weighs. A lying cylinder rolls when pushed across
    its axis (unless so heavy that the robot cannot tip it over its 32-sided hull's edges,
    about 30 cm thick) and slides, heavily, when pushed along it. A little angular damping
    (0.2/s) stands in for rolling resistance, which PhysX lacks. The density is chosen so
    that boxes and upright cylinders of the sizes the thesis used mostly block, as the
    thesis found, while small ones do not: that is the physics deciding, not the shape.

What is randomised (one sampler per scene family, each from a ``np.random.Generator``)
    :func:`sample_clutter` (5.6.1): 0-12 objects of the four shapes, every dimension
    10-40 cm, centres 0.3-2.0 m ahead and within 1 m to either side, any yaw, apart from
    each other and from the robot. :func:`sample_body` (5.6.2.1): 0-12 fixed boxes of
    5-20 cm hanging anywhere in the cubic metre in front of the robot. :func:`sample_ramp`
    (5.6.2.2): one ramp, its toe 0.3-0.9 m ahead, facing -90..90 deg, 0.5-1.5 m wide and
    long, 2-40 deg steep. :func:`sample_gap` (5.6.2.3): one gap whose near edge is
    10-100 cm ahead of the robot's front, 5-50 cm wide, turned -60..60 deg.

What the behaviours do
    ``TraverseWorld.move(rotate_deg)``: rotate in place by 0, +-20, +-40 or +-60 deg (left
    positive), then drive 70 cm forward (thesis 5.3.2); each phase has a time limit. The
    result is the robot's own reading (:class:`sim.robots.mobile.Odometry`): success if its
    heading changed by the rotation within +-5 deg and its dead-reckoned displacement is
    65-75 cm, while its encoders agreed with its gyro (no slip) and it did not tip over
    (IMU tilt under 25 deg). Build a fresh world for every behaviour (Algorithm 1's "reset robot and
    object positions": a new world is the reset, and costs a few milliseconds).

What ground truth is kept (``TraverseWorld.truth``, for reports only, never for learning)
    The robot's true pose (x, y, yaw, z) before and after, its tilt, whether it fell (its
    base ended more than 5 cm below the floor: into the gap), whether it touched an object or a ramp
    (a contact with a non-zero impulse), and each object's position before and after.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from functools import lru_cache

import numpy as np
import sapien

from afford.features import RangeImage
from afford.features.errors import DataError
from afford.sim.camera import MeshInstance
from afford.sim.layout import LayoutError
from afford.sim.objects import SHAPES, SOLID_SHAPES, ObjectSpec, box_mesh, build_object, object_mesh, yaw_quaternion
from afford.sim.robots.mobile import MobileRobot, MobileRobotConfig, Odometry
from afford.sim.scanner import RangeScanner, ScannerConfig

__all__ = [
    "Item", "Ramp", "Gap", "TraverseLayout", "TraverseConfig", "TraverseWorld", "ROTATIONS",
    "sample_clutter", "sample_body", "sample_ramp", "sample_gap",
    "parse_layout", "layout_toml", "check_layout", "TraverseLayoutFiles", "build_items",
]

#: The seven behaviours' rotations, degrees (left positive), right to left.
ROTATIONS = (-60.0, -40.0, -20.0, 0.0, 20.0, 40.0, 60.0)

_SIZES = {"box": 3, "cylinder": 2, "lying-cylinder": 2, "sphere": 1}


def _finite(*values: float) -> bool:
    return all(isinstance(v, (int, float)) and math.isfinite(v) for v in values)


# -- layout data ------------------------------------------------------------------------------
@dataclass(frozen=True)
class Item:
    """One object in the robot's start frame (metres, degrees).

    ``size`` as in :class:`sim.objects.ObjectSpec`: box edges, ``[diameter, length]`` for
    cylinders, ``[diameter]`` for spheres. ``position`` is the centre's (x, y); ``z`` the
    height of the object's bottom above the floor (``None``: on the floor). A ``fixed``
    object does not move (a hanging box); one that is not fixed rests on the floor.
    """

    shape: str
    size: tuple[float, ...]
    position: tuple[float, float]
    yaw: float = 0.0
    z: float | None = None
    fixed: bool = False

    def __post_init__(self) -> None:
        object.__setattr__(self, "size", tuple(float(v) for v in self.size))
        object.__setattr__(self, "position", tuple(float(v) for v in self.position))
        if len(self.position) != 2:
            raise DataError("an object's position is [x, y] of its centre, ahead and to the left of the robot")
        self.spec  # validates shape and size  # noqa: B018
        if not _finite(self.yaw) or (self.z is not None and not _finite(self.z)):
            raise DataError("an object's yaw and z must be finite numbers")
        if self.z is not None and not (0.0 <= self.z <= 3.0):
            raise DataError(f"an object's z (its bottom's height) must be 0-3 m, got {self.z}")
        if self.bottom > 0.0 and not self.fixed:
            raise DataError("only a fixed object can hang above the floor (z > 0 needs fixed = true)")

    @property
    def spec(self) -> ObjectSpec:
        """The object as :mod:`sim.objects` builds and meshes it."""
        return ObjectSpec(self.shape, self.size, self.position, self.yaw)

    @property
    def bottom(self) -> float:
        return 0.0 if self.z is None else float(self.z)

    @property
    def top(self) -> float:
        return self.bottom + self.spec.height

    def footprint(self) -> tuple[tuple[float, float], tuple[float, float], float]:
        """(centre, half extents, yaw in degrees) of the object's footprint rectangle."""
        e = self.spec.extents
        return self.position, (e[0] / 2, e[1] / 2), self.yaw

    def to_dict(self) -> dict:
        return {"shape": self.shape, "size": list(self.size), "position": list(self.position),
                "yaw": self.yaw, "z": self.z, "fixed": self.fixed}


@dataclass(frozen=True)
class Ramp:
    """A static wedge: ``position`` is the centre of its low edge (the toe), ``yaw`` the
    direction it climbs (0: straight ahead, head-on), ``length`` its horizontal run,
    ``width`` its extent along the toe, ``slope`` its angle in degrees; its high end is a
    vertical face ``length * tan(slope)`` high."""

    position: tuple[float, float]
    yaw: float = 0.0
    width: float = 1.0
    length: float = 1.0
    slope: float = 10.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "position", tuple(float(v) for v in self.position))
        if len(self.position) != 2:
            raise DataError("a ramp's position is [x, y] of its toe's centre")
        if not _finite(*self.position, self.yaw, self.width, self.length, self.slope):
            raise DataError("a ramp's position, yaw, width, length and slope must be finite numbers")
        if not (0.05 <= self.width <= 10.0 and 0.05 <= self.length <= 10.0):
            raise DataError(f"a ramp's width and length must be 0.05-10 m, got {self.width} and {self.length}")
        if not (0.5 <= self.slope <= 60.0):
            raise DataError(f"a ramp's slope must be 0.5-60 degrees, got {self.slope}")

    @property
    def height(self) -> float:
        return self.length * math.tan(math.radians(self.slope))

    @property
    def direction(self) -> np.ndarray:
        th = math.radians(self.yaw)
        return np.array([math.cos(th), math.sin(th)])

    def footprint(self) -> tuple[tuple[float, float], tuple[float, float], float]:
        c = np.asarray(self.position) + self.direction * self.length / 2
        return (float(c[0]), float(c[1])), (self.length / 2, self.width / 2), self.yaw

    def vertices(self) -> np.ndarray:
        """The wedge's six corners in its own frame (toe centre at the origin, x up the slope)."""
        w, L, h = self.width / 2, self.length, self.height
        return np.array([[0, -w, 0], [0, w, 0], [L, -w, 0], [L, w, 0], [L, -w, h], [L, w, h]], dtype=float)

    def to_dict(self) -> dict:
        return {"position": list(self.position), "yaw": self.yaw, "width": self.width,
                "length": self.length, "slope": self.slope}


_WEDGE_TRIANGLES = np.array([
    [0, 2, 1], [1, 2, 3],          # bottom
    [0, 1, 5], [0, 5, 4],          # slope
    [2, 4, 5], [2, 5, 3],          # high end
    [0, 4, 2], [1, 3, 5],          # sides
], dtype=np.uint32)


@dataclass(frozen=True)
class Gap:
    """A trench across the floor: its near edge ``distance`` ahead of the robot's front
    (measured along the robot's heading), ``width`` across, turned by ``yaw`` degrees
    (0: the edge square to the robot's heading)."""

    distance: float
    width: float
    yaw: float = 0.0

    def __post_init__(self) -> None:
        if not _finite(self.distance, self.width, self.yaw):
            raise DataError("a gap's distance, width and yaw must be finite numbers")
        if not (0.0 <= self.distance <= 5.0):
            raise DataError(f"a gap's distance must be 0-5 m, got {self.distance}")
        if not (0.01 <= self.width <= 2.0):
            raise DataError(f"a gap's width must be 0.01-2 m, got {self.width}")
        if not (-80.0 <= self.yaw <= 80.0):
            raise DataError(f"a gap's yaw must be -80..80 degrees, got {self.yaw}")

    @property
    def normal(self) -> np.ndarray:
        """Unit vector across the gap, away from the robot."""
        th = math.radians(self.yaw)
        return np.array([math.cos(th), math.sin(th)])

    def near_point(self, front: float) -> np.ndarray:
        """Where the near edge crosses the robot's heading line (robot front at ``front``)."""
        return np.array([front + self.distance, 0.0])

    def to_dict(self) -> dict:
        return {"distance": self.distance, "width": self.width, "yaw": self.yaw}


@dataclass(frozen=True)
class TraverseLayout:
    """Everything in a traverse world besides the robot and the floor."""

    items: tuple[Item, ...] = ()
    ramps: tuple[Ramp, ...] = ()
    gaps: tuple[Gap, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "items", tuple(self.items))
        object.__setattr__(self, "ramps", tuple(self.ramps))
        object.__setattr__(self, "gaps", tuple(self.gaps))
        if len(self.gaps) > 1:
            raise DataError("a traverse world has at most one gap")

    def to_dict(self) -> dict:
        return {"items": [i.to_dict() for i in self.items], "ramps": [r.to_dict() for r in self.ramps],
                "gaps": [g.to_dict() for g in self.gaps]}

    @classmethod
    def from_dict(cls, d: dict) -> "TraverseLayout":
        return cls(tuple(Item(**{**i, "size": tuple(i["size"]), "position": tuple(i["position"])})
                         for i in d.get("items", ())),
                   tuple(Ramp(**{**r, "position": tuple(r["position"])}) for r in d.get("ramps", ())),
                   tuple(Gap(**g) for g in d.get("gaps", ())))


# -- settings ---------------------------------------------------------------------------------
@dataclass(frozen=True)
class TraverseConfig:
    """Physics and sensing settings of the traverse worlds (metres, seconds, kg/m^3)."""

    timestep: float = 1 / 100
    floor_friction: float = 0.5
    """Floor, slabs and ramps."""
    object_friction: float = 0.5
    """Objects (PhysX averages: 0.5 against the floor, 0.3 against the robot's smooth shell)."""
    density: float = 2000.0
    """One density for every object: mass follows from volume alone."""
    rolling_damping: float = 0.2
    """Angular damping of the objects (1/s), standing in for rolling resistance."""
    pit_depth: float = 0.5
    """Depth of a gap (the trench's bottom below the floor)."""
    robot: MobileRobotConfig = field(default_factory=MobileRobotConfig)
    scanner: ScannerConfig = field(default_factory=ScannerConfig)
    watch_every: int = 2
    """Look for contacts every this many physics steps (ground truth only)."""


# -- geometry helpers -------------------------------------------------------------------------
def _corners(centre, half, yaw_deg: float) -> np.ndarray:
    th = math.radians(yaw_deg)
    rot = np.array([[math.cos(th), -math.sin(th)], [math.sin(th), math.cos(th)]])
    local = np.array([[-1, -1], [1, -1], [1, 1], [-1, 1]], dtype=float) * np.asarray(half)
    return local @ rot.T + np.asarray(centre, dtype=float)


def _rects_overlap(a, b, margin: float = 0.0) -> bool:
    """Do two yawed rectangles ``(centre, half, yaw)`` come closer than ``margin``? (separating axes)

    Rectangles whose bounding circles are apart are answered first without numpy: a room's
    layout check compares thousands of pairs and nearly all of them are far apart."""
    (ax, ay), (ahx, ahy) = a[0], a[1]
    (bx, by), (bhx, bhy) = b[0], b[1]
    m = margin / 2
    if math.hypot(ax - bx, ay - by) > math.hypot(ahx + m, ahy + m) + math.hypot(bhx + m, bhy + m):
        return False
    ca = _corners(a[0], np.asarray(a[1]) + m, a[2])
    cb = _corners(b[0], np.asarray(b[1]) + m, b[2])
    for corners in (ca, cb):
        for k in range(2):
            axis = corners[k + 1] - corners[k]
            axis = np.array([-axis[1], axis[0]]) / np.linalg.norm(axis)
            pa, pb = ca @ axis, cb @ axis
            if pa.max() < pb.min() or pb.max() < pa.min():
                return False
    return True


def _robot_footprint(robot: MobileRobotConfig):
    return (0.0, 0.0), (robot.length / 2, robot.width / 2), 0.0


def check_layout(layout: TraverseLayout, robot: MobileRobotConfig = MobileRobotConfig(), margin: float = 0.02) -> None:
    """Raise ValueError (one sentence) if the layout cannot be the start of an episode.

    Nothing may stand in the robot's start footprint (up to its height), a loose object may
    not overlap another object or a ramp, and a gap's near edge must lie ahead of the robot.
    """
    me = _robot_footprint(robot)
    for kind, entries in (("object", layout.items), ("ramp", layout.ramps)):
        for i, e in enumerate(entries):
            if max(abs(e.position[0]), abs(e.position[1])) > _REACH:
                raise DataError(f"{kind} {i} at {list(e.position)} lies off the floor, which reaches {_REACH:g} m "
                                "about the robot; move it nearer")
    # each footprint and height once: the pairs below would rebuild them thousands of times
    feet, bottoms, tops = [it.footprint() for it in layout.items], [it.bottom for it in layout.items], [it.top for it in layout.items]
    ramps = [r.footprint() for r in layout.ramps]
    for i in range(len(ramps)):
        for j in range(i + 1, len(ramps)):
            if _rects_overlap(ramps[i], ramps[j]):
                raise DataError(f"ramps {i} and {j} overlap; move one of them")
    for i, it in enumerate(layout.items):
        if bottoms[i] < robot.height + margin and _rects_overlap(me, feet[i], margin):
            raise DataError(f"object {i} at {list(it.position)} overlaps the robot's start position; move it away")
    for i, r in enumerate(layout.ramps):
        if _rects_overlap(me, ramps[i], margin):
            raise DataError(f"ramp {i} at {list(r.position)} overlaps the robot's start position; move it away")
    for i, a in enumerate(layout.items):
        for j in range(i + 1, len(layout.items)):
            if a.fixed and layout.items[j].fixed:
                continue  # fixed bodies may interpenetrate: nothing moves them
            if bottoms[i] < tops[j] and bottoms[j] < tops[i] and _rects_overlap(feet[i], feet[j]):
                raise DataError(f"objects {i} and {j} overlap; move one of them")
        if not a.fixed:
            for k in range(len(ramps)):
                if _rects_overlap(feet[i], ramps[k]):
                    raise DataError(f"object {i} overlaps ramp {k}; a loose object must stand on the floor")
    for i, g in enumerate(layout.gaps):
        p = g.near_point(robot.length / 2)
        side = (_corners(*me) - p) @ g.normal
        if side.max() > -margin:
            raise DataError(f"gap {i}'s near edge runs under the robot's start position; "
                             "give it a larger distance or a smaller yaw")


# -- sampling ---------------------------------------------------------------------------------
def _place(rng: np.random.Generator, make, layout_items: list[Item], robot: MobileRobotConfig,
           tries: int = 50) -> Item | None:
    """Draw ``make(rng)`` until it fits beside the robot and the other items (or give up)."""
    me = _robot_footprint(robot)
    for _ in range(tries):
        it = make(rng)
        if it.bottom < robot.height + 0.02 and _rects_overlap(me, it.footprint(), 0.05):
            continue
        if any(not (it.fixed and o.fixed) and it.bottom < o.top and o.bottom < it.top
               and _rects_overlap(it.footprint(), o.footprint(), 0.02) for o in layout_items):
            continue
        return it
    return None


def _round(v: float) -> float:
    return float(round(float(v), 4))


def sample_clutter(rng: np.random.Generator, max_objects: int = 12, size_range: tuple[float, float] = (0.10, 0.40),
                   x_range: tuple[float, float] = (0.3, 2.0), y_range: tuple[float, float] = (-1.0, 1.0),
                   shapes: tuple[str, ...] = SOLID_SHAPES, robot: MobileRobotConfig = MobileRobotConfig(),
                   min_objects: int = 0) -> TraverseLayout:
    """``min_objects``-``max_objects`` loose objects of random shape (one of ``shapes``), size,
    place and yaw (thesis 5.6.1)."""
    lo, hi = size_range
    if not (0.01 <= lo <= hi <= 1.0):
        raise DataError(f"object sizes must satisfy 0.01 <= min <= max <= 1.0 m, got {lo} and {hi}")

    def make(g: np.random.Generator) -> Item:
        shape = shapes[int(g.integers(len(shapes)))]
        size = tuple(_round(v) for v in g.uniform(lo, hi, size=_SIZES[shape]))
        pos = (_round(g.uniform(*x_range)), _round(g.uniform(*y_range)))
        return Item(shape, size, pos, _round(g.uniform(0.0, 360.0)))

    items: list[Item] = []
    for _ in range(int(rng.integers(min_objects, max_objects + 1))):
        it = _place(rng, make, items, robot)
        if it is not None:
            items.append(it)
    return TraverseLayout(items=tuple(items))


def sample_body(rng: np.random.Generator, max_boxes: int = 12, size_range: tuple[float, float] = (0.05, 0.20),
                x_range: tuple[float, float] = (0.3, 1.3), y_range: tuple[float, float] = (-0.5, 0.5),
                z_range: tuple[float, float] = (0.0, 1.0),
                robot: MobileRobotConfig = MobileRobotConfig()) -> TraverseLayout:
    """0-``max_boxes`` fixed boxes hanging in the cubic metre in front of the robot (5.6.2.1)."""
    lo, hi = size_range

    def make(g: np.random.Generator) -> Item:
        size = tuple(_round(v) for v in g.uniform(lo, hi, size=3))
        pos = (_round(g.uniform(*x_range)), _round(g.uniform(*y_range)))
        z = _round(g.uniform(z_range[0], max(z_range[0], z_range[1] - size[2])))
        return Item("box", size, pos, _round(g.uniform(0.0, 360.0)), z=z, fixed=True)

    items: list[Item] = []
    for _ in range(int(rng.integers(max_boxes + 1))):
        it = _place(rng, make, items, robot)
        if it is not None:
            items.append(it)
    return TraverseLayout(items=tuple(items))


def sample_ramp(rng: np.random.Generator, x_range: tuple[float, float] = (0.3, 0.9),
                y_range: tuple[float, float] = (-0.5, 0.5), yaw_range: tuple[float, float] = (-90.0, 90.0),
                width_range: tuple[float, float] = (0.5, 1.5), length_range: tuple[float, float] = (0.5, 1.5),
                slope_range: tuple[float, float] = (2.0, 40.0), robot: MobileRobotConfig = MobileRobotConfig(),
                tries: int = 100) -> TraverseLayout:
    """One ramp of random place, orientation, width, length and slope (5.6.2.2).

    The thesis gives no slope range. Slopes reach 40 degrees because the robot's critical
    slope on an oblique ramp is 25-38 degrees: with 2-30, the oblique ramps that stop it
    were hardly ever met, and the learned critical slopes (Table 5.1) were pulled towards
    12-15 degrees at every orientation."""
    me = _robot_footprint(robot)
    for _ in range(tries):
        ramp = Ramp((_round(rng.uniform(*x_range)), _round(rng.uniform(*y_range))), _round(rng.uniform(*yaw_range)),
                    _round(rng.uniform(*width_range)), _round(rng.uniform(*length_range)),
                    _round(rng.uniform(*slope_range)))
        if not _rects_overlap(me, ramp.footprint(), 0.05):
            return TraverseLayout(ramps=(ramp,))
    raise DataError("could not place a ramp clear of the robot; widen the ramps' position range")


def sample_gap(rng: np.random.Generator, distance_range: tuple[float, float] = (0.10, 1.00),
               width_range: tuple[float, float] = (0.05, 0.50), yaw_range: tuple[float, float] = (-60.0, 60.0),
               robot: MobileRobotConfig = MobileRobotConfig(), tries: int = 100) -> TraverseLayout:
    """One gap 10-100 cm ahead of the robot's front, of random width and orientation (5.6.2.3)."""
    for _ in range(tries):
        gap = Gap(_round(rng.uniform(*distance_range)), _round(rng.uniform(*width_range)),
                  _round(rng.uniform(*yaw_range)))
        layout = TraverseLayout(gaps=(gap,))
        try:
            check_layout(layout, robot)
        except ValueError:
            continue
        return layout
    raise DataError("could not place a gap ahead of the robot; widen the gaps' distance range")


# -- layout files -----------------------------------------------------------------------------
_KEYS = {
    "object": ({"shape", "size", "position"}, {"yaw", "z", "fixed"}),
    "ramp": ({"position"}, {"yaw", "width", "length", "slope"}),
    "gap": ({"distance", "width"}, {"yaw"}),
}


def _number(value, what: str, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise LayoutError(f"{where}: {what} must be a number")
    return float(value)


def _numbers(value, what: str, where: str) -> tuple[float, ...]:
    if not isinstance(value, list) or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise LayoutError(f"{where}: {what} must be a list of numbers")
    return tuple(float(v) for v in value)


def parse_layout(text: str, source: str = "layout") -> TraverseLayout:
    """A traverse layout from TOML text: ``[[object]]``, ``[[ramp]]`` and ``[[gap]]`` entries.

    .. code-block:: toml

        [[object]]
        shape = "box"               # box | cylinder | lying-cylinder | sphere
        size = [0.3, 0.3, 0.3]      # metres: box edges, [diameter, length], or [diameter]
        position = [0.8, 0.0]       # x ahead, y to the left, from the robot's centre
        yaw = 0.0                   # degrees
        z = 0.5                     # optional: the bottom's height (needs fixed = true)
        fixed = false               # true: does not move (a hanging box)

        [[ramp]]
        position = [0.5, 0.0]       # centre of the low edge
        yaw = 0.0                   # climbing direction, 0 = head-on
        width = 1.0
        length = 1.0                # horizontal run; height = length * tan(slope)
        slope = 8.0                 # degrees

        [[gap]]
        distance = 0.3              # near edge ahead of the robot's front
        width = 0.2
        yaw = 0.0                   # 0 = edge square to the heading

    Every mistake raises :class:`sim.layout.LayoutError`: one sentence naming the file
    and the entry.
    """
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise LayoutError(f"{source} is not valid TOML ({exc})") from None
    unknown = set(doc) - set(_KEYS) - {"scene"}  # the scene it names is checked when the file is read
    if unknown:
        raise LayoutError(f"{source}: unknown table {sorted(unknown)[0]!r}; a traverse layout holds "
                          "[[object]], [[ramp]] and [[gap]] entries")
    parsed: dict[str, list] = {k: [] for k in _KEYS}
    for kind, (required, optional) in _KEYS.items():
        entries = doc.get(kind, [])
        if not isinstance(entries, list):
            raise LayoutError(f"{source}: {kind!r} must be a list of [[{kind}]] tables")
        for i, entry in enumerate(entries):
            where = f"{source}, {kind} {i}"
            if not isinstance(entry, dict):
                raise LayoutError(f"{where}: each {kind} must be a [[{kind}]] table, not {type(entry).__name__}")
            extra = set(entry) - required - optional
            if extra:
                raise LayoutError(f"{where}: unknown key {sorted(extra)[0]!r}; known keys: "
                                  f"{', '.join(sorted(required | optional))}")
            missing = sorted(required - set(entry))
            if missing:
                raise LayoutError(f"{where}: missing {missing[0]!r}")
            try:
                parsed[kind].append(_entry(kind, entry, where))
            except LayoutError:
                raise
            except (ValueError, TypeError) as exc:
                raise LayoutError(f"{where}: {exc}") from None
    try:
        return TraverseLayout(tuple(parsed["object"]), tuple(parsed["ramp"]), tuple(parsed["gap"]))
    except ValueError as exc:
        raise LayoutError(f"{source}: {exc}") from None


def _entry(kind: str, e: dict, where: str):
    if kind == "object":
        shape = e["shape"]
        if shape not in SHAPES:
            raise LayoutError(f"{where}: unknown shape {shape!r}; known shapes: {', '.join(SHAPES)}")
        fixed = e.get("fixed", False)
        if not isinstance(fixed, bool):
            raise LayoutError(f"{where}: fixed must be true or false")
        z = e.get("z")
        return Item(shape, _numbers(e["size"], "size", where), _numbers(e["position"], "position", where),
                    _number(e.get("yaw", 0.0), "yaw", where), None if z is None else _number(z, "z", where), fixed)
    if kind == "ramp":
        position = _numbers(e["position"], "position", where)
        if len(position) != 2:
            raise LayoutError(f"{where}: position must be [x, y] of the ramp's toe")
        return Ramp(position, *(_number(e.get(k, d), k, where) for k, d in
                                (("yaw", 0.0), ("width", 1.0), ("length", 1.0), ("slope", 10.0))))
    return Gap(_number(e["distance"], "distance", where), _number(e["width"], "width", where),
               _number(e.get("yaw", 0.0), "yaw", where))


def layout_toml(layout: TraverseLayout) -> str:
    """The TOML text of a layout (the inverse of :func:`parse_layout`)."""
    def nums(v) -> str:
        return "[" + ", ".join(repr(float(x)) for x in v) + "]"

    lines: list[str] = []
    for it in layout.items:
        lines += ["[[object]]", f'shape = "{it.shape}"', f"size = {nums(it.size)}",
                  f"position = {nums(it.position)}", f"yaw = {float(it.yaw)!r}"]
        if it.z is not None:
            lines.append(f"z = {float(it.z)!r}")
        lines += [f"fixed = {'true' if it.fixed else 'false'}", ""]
    for r in layout.ramps:
        lines += ["[[ramp]]", f"position = {nums(r.position)}", f"yaw = {float(r.yaw)!r}",
                  f"width = {float(r.width)!r}", f"length = {float(r.length)!r}", f"slope = {float(r.slope)!r}", ""]
    for g in layout.gaps:
        lines += ["[[gap]]", f"distance = {float(g.distance)!r}", f"width = {float(g.width)!r}",
                  f"yaw = {float(g.yaw)!r}", ""]
    return "\n".join(lines)


class TraverseLayoutFiles:
    """What every scene whose layouts are :class:`TraverseLayout` does with layout files."""

    name = ""
    layout_format = "traverse"  # robot-centred: x ahead of the robot, y to its left

    def parse_layout(self, text: str, source: str = "layout") -> TraverseLayout:
        return parse_layout(text, source)

    def layout_toml(self, layout: TraverseLayout) -> str:
        return layout_toml(layout)

    def layout_json(self, layout: TraverseLayout) -> dict:
        return layout.to_dict()

    def _check_kind(self, layout) -> None:
        if not isinstance(layout, TraverseLayout):
            raise DataError(f"that is not a layout of scene {self.name!r}")


def build_items(scene: sapien.Scene, items, density: float, friction: float, rolling_damping: float):
    """The layout's objects as rigid bodies on the floor: fixed ones kinematic, loose ones with
    a little angular damping for rolling resistance. Returns (entities, their components)."""
    material = sapien.physx.PhysxMaterial(friction, friction, 0.0)
    bodies, components = [], []
    for it in items:
        body = build_object(scene, it.spec, it.bottom, density, material)
        comp = body.find_component_by_type(sapien.physx.PhysxRigidDynamicComponent)
        if it.fixed:
            comp.set_kinematic(True)
        else:
            comp.set_max_depenetration_velocity(1.0)
            comp.set_angular_damping(rolling_damping)
        bodies.append(body)
        components.append(comp)
    return bodies, components


# -- the world --------------------------------------------------------------------------------
@lru_cache(maxsize=4)
def _scanner(config: ScannerConfig, origin: tuple[float, float, float]) -> RangeScanner:
    return RangeScanner(config, origin)


_FLOOR_HALF = 10.0  # the floor and the slabs reach this far: well beyond the scanner's range
#: Objects and ramps must stand within this distance (each axis) of the robot's start.
_REACH = _FLOOR_HALF - 1.0


class TraverseWorld:
    """A fresh SAPIEN scene: the floor (or a gap's slabs), the layout, the robot at the origin.

    ``rng`` draws the scanner's noise. Build one world per behaviour: ``scan`` once from the
    start, then for each behaviour a new world and ``move``.
    """

    def __init__(self, layout: TraverseLayout, rng: np.random.Generator, config: TraverseConfig = TraverseConfig()):
        self.layout = layout
        self.rng = rng
        self.config = c = config
        self.scene = sapien.Scene(systems=[sapien.physx.PhysxCpuSystem()])
        self.scene.set_timestep(c.timestep)
        floor = sapien.physx.PhysxMaterial(c.floor_friction, c.floor_friction, 0.0)
        self._static: list[MeshInstance] = []
        self._build_floor(floor)
        self.ramps = [self._build_ramp(r, floor) for r in layout.ramps]
        self.bodies, self.components = build_items(self.scene, layout.items, c.density, c.object_friction,
                                                   c.rolling_damping)
        self.robot = MobileRobot(self.scene, c.robot)
        self.start = self.robot.pose()
        self._item_start = [np.asarray(b.pose.p, dtype=float) for b in self.bodies]
        self._robot_links = set(self.robot.articulation.get_links())
        self._touchable = {comp: ("object", i) for i, comp in enumerate(self.components)}
        self._touchable.update({r: ("ramp", i) for i, r in enumerate(self.ramps)})
        self.touched: set[tuple[str, int]] = set()
        self._steps = 0
        self.last: Odometry | None = None

    # -- building --------------------------------------------------------------------------
    def _add_static_box(self, centre, half, yaw_deg: float, material) -> None:
        pose = sapien.Pose(list(centre), yaw_quaternion(yaw_deg))
        b = self.scene.create_actor_builder()
        b.add_box_collision(half_size=list(half), material=material)
        b.set_initial_pose(pose)
        b.build_static(name="slab")
        v, t = box_mesh(half)
        self._static.append(MeshInstance(v, t, np.asarray(pose.p), np.asarray(pose.q)))

    def _build_floor(self, material) -> None:
        c = self.config
        if not self.layout.gaps:
            self.scene.add_ground(0.0, render=False, material=material)
            self._static.append(MeshInstance(*_plane(0.0), np.zeros(3), np.array([1.0, 0, 0, 0])))
            return
        gap = self.layout.gaps[0]
        n = gap.normal
        p = gap.near_point(c.robot.length / 2)
        half = (_FLOOR_HALF, _FLOOR_HALF, c.pit_depth / 2)
        near = p - n * _FLOOR_HALF
        far = p + n * (gap.width + _FLOOR_HALF)
        for centre in (near, far):
            self._add_static_box((centre[0], centre[1], -c.pit_depth / 2), half, gap.yaw, material)
        self.scene.add_ground(-c.pit_depth, render=False, material=material)
        self._static.append(MeshInstance(*_plane(-c.pit_depth), np.zeros(3), np.array([1.0, 0, 0, 0])))

    def _build_ramp(self, ramp: Ramp, material):
        shape = sapien.physx.PhysxCollisionShapeConvexMesh(
            vertices=ramp.vertices().astype(np.float32), scale=np.ones(3, dtype=np.float32), material=material)
        body = sapien.physx.PhysxRigidStaticComponent()
        body.attach(shape)
        entity = sapien.Entity()
        entity.name = "ramp"
        entity.add_component(body)
        entity.pose = sapien.Pose([ramp.position[0], ramp.position[1], 0.0], yaw_quaternion(ramp.yaw))
        self.scene.add_entity(entity)
        self._static.append(MeshInstance(ramp.vertices(), _WEDGE_TRIANGLES, np.asarray(entity.pose.p),
                                         np.asarray(entity.pose.q)))
        return body

    # -- sensing ---------------------------------------------------------------------------
    def meshes(self) -> list[MeshInstance]:
        """Everything the scanner can see, posed as it is now (the robot's body marked own)."""
        out = list(self._static)
        for it, body in zip(self.layout.items, self.bodies):
            v, t = object_mesh(it.spec)
            out.append(MeshInstance(v, t, np.asarray(body.pose.p), np.asarray(body.pose.q)))
        pose = self.robot.base.entity_pose
        for centre, half in self.config.robot.body_boxes()[:1]:  # the head holds the scanner: not in view
            v, t = box_mesh(half)
            out.append(MeshInstance(v + np.asarray(centre), t, np.asarray(pose.p), np.asarray(pose.q), own_body=True))
        return out

    @property
    def scanner(self) -> RangeScanner:
        return _scanner(self.config.scanner, self.config.robot.scanner_mount)

    def scan(self) -> RangeImage:
        """One noisy 360 x 360 range image from where the robot stands, in its frame."""
        world_to_robot = self.robot.base.entity_pose.inv().to_transformation_matrix()
        return self.scanner.scan(self.meshes(), self.rng, world_to_robot)

    # -- acting ----------------------------------------------------------------------------
    def _watch(self) -> None:
        self._steps += 1
        if self._steps % self.config.watch_every:
            return
        mine, touchable, touched = self._robot_links, self._touchable, self.touched
        for contact in self.scene.get_contacts():
            a, b = contact.bodies
            for other in ((b,) if a in mine else ()) + ((a,) if b in mine else ()):
                key = touchable.get(other)
                if key is not None and key not in touched and any(np.any(p.impulse) for p in contact.points):
                    touched.add(key)

    def move(self, rotate_deg: float, drive_m: float = 0.70) -> Odometry:
        """Run one behaviour: rotate in place, then drive forward; the robot's own reading."""
        self.last = self.robot.move(rotate_deg, drive_m, on_step=self._watch)
        return self.last

    # -- ground truth ----------------------------------------------------------------------
    def truth(self) -> dict:
        """What physically is, for reports only."""
        return {
            "start": self.start.to_dict(),
            "end": self.robot.pose().to_dict(),
            "fell": self.robot.fell(),
            "tilt_deg": self.robot.tilt(),
            "contact": bool(self.touched),
            "touched_objects": sorted(i for kind, i in self.touched if kind == "object"),
            "touched_ramps": sorted(i for kind, i in self.touched if kind == "ramp"),
            "objects": [{"start": s.tolist(), "end": np.asarray(b.pose.p, dtype=float).tolist()}
                        for s, b in zip(self._item_start, self.bodies)],
        }


def _plane(z: float) -> tuple[np.ndarray, np.ndarray]:
    h = _FLOOR_HALF
    v = np.array([[-h, -h, z], [h, -h, z], [h, h, z], [-h, h, z]], dtype=float)
    return v, np.array([[0, 1, 2], [0, 2, 3]], dtype=np.uint32)
