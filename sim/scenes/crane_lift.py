"""``crane-lift``: a mobile robot with a crane moves and lifts (thesis chapter 7).

What the robot has
    The chapter-5 base with a slewing crane and a magnet plate (``sim.robots.crane``) and
    the 3D range scanner on its front (``sim.scanner``, 360 x 360 after down-scaling); it
    perceives objects as regions that stand out of its scan of the empty floor, 44 features
    each (``features.image_objects``). The world is in ``sim.crane``.

What is randomised (per episode, from the episode's seed)
    One object: box, upright cylinder, lying cylinder or sphere (equally likely); each
    dimension uniform in 20-40 cm; its centre at a bearing uniform in -90..90 deg and a
    distance uniform up to 1 m of the robot's centre (redrawn until it clears the robot's
    footprint); yaw uniform. Range noise. ``--objects N`` draws N apart (planning), and
    ``button`` adds a fixed flat disc (30 cm across, 6 cm high) for the case study of 7.6.5.

What the behaviours do
    ``move-forward``, ``move-left-30``, ``move-right-30``, ``move-left-60``,
    ``move-right-60``: rotate in place, then drive 40 cm; no target, so every object the
    robot sees may change. ``lift``: the crane lowers its magnet over the target, grips
    what it can and raises it (it does nothing if the target lies beyond the crane).

The loop
    Algorithm 1 with a look after: one random environment scanned once, then every
    behaviour from the same start in a freshly built world, each followed by a scan; the
    effect is after - before of the tracked object, to be clustered (``afford cluster
    --method kmeans --k K``, one k per behaviour: the scene's defaults are 2 for lift, as
    the thesis, and 4 for the moves).

What ground truth is kept (for reports only)
    The object's shape and size, its pose before and after, whether it hangs from the
    magnet, the robot's true pose, whether the crane reached, whether the robot touched
    the object, and the outcome (``lifted``, ``left-view``, ``pushed``, ``no-change``).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from afford.features.errors import DataError
from afford.features.image_objects import image_object_schema
from afford.sim.behaviors import Behavior, Execution
from afford.sim.crane import CRANE_OUTCOMES, DRIVE, CraneWorld, CraneWorldConfig
from afford.sim.objects import SOLID_SHAPES as SHAPES
from afford.sim.registry import register_scene
from afford.sim.traverse import Item, TraverseLayout, TraverseLayoutFiles, _rects_overlap, _robot_footprint, check_layout

__all__ = ["CraneLiftScene", "CraneSceneConfig", "CRANE_BEHAVIORS", "BUTTON"]

_SIZES = {"box": 3, "cylinder": 2, "lying-cylinder": 2, "sphere": 1}
#: The 7.6.5 case study's button: a fixed flat disc on the floor.
BUTTON = dict(shape="cylinder", size=(0.30, 0.06), fixed=True)


def _move_name(rotate: float) -> str:
    return "move-forward" if rotate == 0 else f"move-{'left' if rotate > 0 else 'right'}-{abs(rotate):g}"


def _move(rotate: float):
    def controller(world: CraneWorld, target, alpha) -> Execution:
        odometry = world.move(rotate, DRIVE)
        return Execution(True, reading=odometry.to_dict())

    return controller


def _lift(world: CraneWorld, target, alpha) -> Execution:
    return Execution(world.lift(target))


CRANE_BEHAVIORS: tuple[Behavior, ...] = tuple(
    Behavior(_move_name(r), (), _move(r), f"rotate {r:+g} deg in place, then drive {100 * DRIVE:.0f} cm", target=None)
    for r in (0.0, 30.0, -30.0, 60.0, -60.0)
) + (Behavior("lift", (), _lift, "lower the crane's magnet over the object, grip, raise"),)


@dataclass(frozen=True)
class CraneSceneConfig:
    size_range: tuple[float, float] = (0.20, 0.40)
    """Each object dimension is uniform in this range (metres)."""
    distance: float = 1.0
    """Objects' centres lie within this distance of the robot's centre."""
    bearing: float = 90.0
    """... and within this bearing either side of its heading (degrees)."""
    world: CraneWorldConfig = field(default_factory=CraneWorldConfig)

    def __post_init__(self) -> None:
        lo, hi = self.size_range
        if not (0.05 <= lo <= hi <= 0.6):
            raise DataError(f"object sizes must satisfy 0.05 <= min <= max <= 0.6 m, got {lo} and {hi}")
        if not (0.4 <= self.distance <= 3.0):
            raise DataError(f"the objects' distance must be 0.4-3 m, got {self.distance}")


@register_scene("crane-lift")
class CraneLiftScene(TraverseLayoutFiles):
    """The chapter 7 mobile crane (see the module docstring for its task sheet)."""

    name = "crane-lift"
    summary = "a mobile robot with a crane moves and lifts one random object (thesis chapter 7)"
    behaviors = CRANE_BEHAVIORS
    labels = "discovered"
    results: tuple[str, ...] = ()
    outcomes = CRANE_OUTCOMES
    loop = "scan"
    options = {
        "size_min": "Smallest object dimension, metres (0.05-0.6).",
        "size_max": "Largest object dimension, metres (0.05-0.6).",
        "distance": "Objects lie within this distance of the robot, metres.",
    }
    sample_options = ("objects", "button")
    #: ``afford cluster``'s defaults: one-level k-means with these k (thesis 7.6.1-7.6.2).
    clustering = {"method": "kmeans", "k": {"lift": 2, "*": 4}}

    def __init__(self, config: CraneSceneConfig | None = None):
        self.config = config or CraneSceneConfig()

    @property
    def schema(self):
        return image_object_schema()

    def describe(self) -> dict:
        d = asdict(self.config)
        d["name"] = self.name
        d["clustering"] = {"method": self.clustering["method"], "k": dict(self.clustering["k"])}
        return d

    def options_from(self, description: dict) -> dict:
        lo, hi = description.get("size_range", self.config.size_range)
        return {"size_min": lo, "size_max": hi, "distance": description.get("distance", self.config.distance)}

    def configure(self, size_min: float | None = None, size_max: float | None = None,
                  distance: float | None = None) -> "CraneLiftScene":
        c = self.config
        lo = c.size_range[0] if size_min is None else float(size_min)
        hi = c.size_range[1] if size_max is None else float(size_max)
        if lo > hi:
            raise DataError(f"the smallest object size ({lo}) is larger than the largest ({hi})")
        from dataclasses import replace

        return type(self)(replace(c, size_range=(lo, hi), distance=c.distance if distance is None else float(distance)))

    # -- layouts ---------------------------------------------------------------------------
    def _object(self, rng: np.random.Generator) -> Item:
        c = self.config
        shape = SHAPES[int(rng.integers(len(SHAPES)))]
        size = tuple(float(round(v, 4)) for v in rng.uniform(*c.size_range, size=_SIZES[shape]))
        bearing = math.radians(rng.uniform(-c.bearing, c.bearing))
        r = c.distance * math.sqrt(rng.uniform(0.0, 1.0))  # uniform over the half disc's area
        pos = (round(r * math.cos(bearing), 4), round(r * math.sin(bearing), 4))
        return Item(shape, size, pos, round(float(rng.uniform(0.0, 360.0)), 3))

    def sample(self, rng: np.random.Generator, objects: int = 1, button: bool = False,
               tries: int = 200) -> TraverseLayout:
        """A random layout: ``objects`` objects apart, clear of the robot (and the button)."""
        robot = self.config.world.robot
        me = _robot_footprint(robot)
        items: list[Item] = []
        wanted = objects + (1 if button else 0)
        for _ in range(tries * wanted):
            if len(items) == wanted:
                break
            it = self._object(rng)
            if button and len(items) == objects:
                it = Item(BUTTON["shape"], BUTTON["size"], it.position, 0.0, fixed=True)
            if _rects_overlap(me, it.footprint(), 0.05):
                continue
            if any(_rects_overlap(it.footprint(), o.footprint(), 0.05) for o in items):
                continue
            items.append(it)
        if len(items) < wanted:
            raise DataError(f"could not place {wanted} objects apart within {self.config.distance:g} m; try fewer")
        return TraverseLayout(items=tuple(items))

    def check_layout(self, layout: TraverseLayout) -> None:
        self._check_kind(layout)
        if layout.ramps or layout.gaps:
            raise DataError("the crane-lift scene has a flat floor: a layout of it holds objects only")
        for i, it in enumerate(layout.items):
            if it.bottom > 0.0:
                raise DataError(f"object {i} hangs above the floor; crane-lift objects stand on it")
        check_layout(layout, self.config.world.robot)

    def build(self, layout: TraverseLayout, rng: np.random.Generator) -> CraneWorld:
        return CraneWorld(layout, rng, self.config.world)
