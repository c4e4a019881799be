"""``traverse-room``: the mobile robot at random places in one walled room (thesis chapter 6).

Chapter 6's robot learned in "a room cluttered with objects of various shapes and size"
and was tested in another room of the same kind.

What the robot has
    The traverse scenes' robot: KURT3D's size, wheel encoders and a gyro, the 3D range
    scanner (``sim.robots.mobile``, ``sim.scanner``), perceiving the whole environment as
    grid features (chapter 6's are ``--grid 30 --layers 1``: 35 100).

What is randomised
    Per room (the scene option ``room``, a seed; the test room is another one): 30 loose
    objects (boxes, upright and lying cylinders, spheres) of 20-40 cm at random places and
    yaws on a 6 x 6 m floor, walled by 1 m segments of 10 cm thick, 60 cm high fixed boxes.
    The options ``clutter`` (how many loose objects) and ``size_min``/``size_max`` (their
    dimensions) make a harder room: more, smaller things.
    The room stays the same from episode to episode; per episode: where the robot stands
    in it and which way it faces (anywhere at least 40 cm inside the walls, on no object),
    and range noise. The world is built in the robot's start frame, as every traverse
    scene's is.

What the behaviours do (``sim.moves``)
    The seven moves of the traverse scenes (rotate 0, +-20, +-40 or +-60 deg, drive 70
    cm), each from the same scanned start in a freshly built world; the result is the
    robot's own odometry reading. Walls and objects block, roll or are shoved as PhysX
    makes them.

What ground truth is kept (reports only)
    As in the traverse scenes: the robot's true pose before and after, whether it fell or
    touched anything, the number of things in the room, the odometry behind each result.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np

from afford.features.errors import DataError
from afford.sim.moves import TraverseScene
from afford.sim.objects import SOLID_SHAPES as SHAPES
from afford.sim.registry import register_scene
from afford.sim.traverse import Item, TraverseLayout, _rects_overlap, check_layout

__all__ = ["RoomScene", "room_items", "walls", "loose_objects", "in_robot_frame"]

HALF = 3.0           # the room's half width (m)
WALL = (1.0, 0.10, 0.60)
N_OBJECTS = 30
SIZES = (0.20, 0.40)
_DIMS = {"box": 3, "cylinder": 2, "lying-cylinder": 2, "sphere": 1}


@lru_cache(maxsize=8)
def room_items(room: int, clutter: int = N_OBJECTS, sizes: tuple[float, float] = SIZES) -> tuple[Item, ...]:
    """Room ``room``'s walls and ``clutter`` objects of ``sizes``, in the room's frame (its centre, metres)."""
    rng = np.random.default_rng(np.random.SeedSequence(entropy=int(room), spawn_key=(3,)))
    return walls() + loose_objects(rng, clutter, sizes=sizes)


def walls() -> tuple[Item, ...]:
    """The room's walls: 1 m segments of fixed boxes around its 6 x 6 m floor."""
    out = []
    for k in range(int(2 * HALF / WALL[0])):
        c = -HALF + WALL[0] * (k + 0.5)
        for x, y, yaw in ((c, HALF, 0.0), (c, -HALF, 0.0), (HALF, c, 90.0), (-HALF, c, 90.0)):
            out.append(Item("box", WALL, (round(x, 4), round(y, 4)), yaw, fixed=True))
    return tuple(out)


def loose_objects(rng: np.random.Generator, n: int, taken: tuple = (), sizes: tuple[float, float] = SIZES) -> tuple[Item, ...]:
    """``n`` loose objects of ``sizes`` (20-40 cm) at random places and yaws on the floor,
    apart from each other, from the walls and from the footprints ``taken``."""
    wall = tuple(w.footprint() for w in walls())
    objects: list[Item] = []
    while len(objects) < n:
        shape = SHAPES[int(rng.integers(len(SHAPES)))]
        size = tuple(round(float(v), 4) for v in rng.uniform(*sizes, size=_DIMS[shape]))
        pos = tuple(round(float(v), 4) for v in rng.uniform(-HALF + 0.3, HALF - 0.3, size=2))
        it = Item(shape, size, pos, round(float(rng.uniform(0.0, 360.0)), 4))
        fp = it.footprint()
        if any(_rects_overlap(fp, w) for w in wall):
            continue  # into a wall (it may touch one)
        if not any(_rects_overlap(fp, o, 0.05) for o in (*taken, *(o.footprint() for o in objects))):
            objects.append(it)
    return tuple(objects)


def in_robot_frame(items: tuple[Item, ...], x: float, y: float, yaw: float) -> TraverseLayout:
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    out = []
    for it in items:
        dx, dy = it.position[0] - x, it.position[1] - y
        pos = (round(c * dx + s * dy, 4), round(-s * dx + c * dy, 4))
        out.append(Item(it.shape, it.size, pos, round((it.yaw - yaw) % 360.0, 4), it.z, it.fixed))
    return TraverseLayout(items=tuple(out))


@register_scene("traverse-room")
class RoomScene(TraverseScene):
    """The robot at a random place in one walled room of random objects (see the module docstring)."""

    summary = "the mobile robot at random places in one walled 6 x 6 m room of 30 objects of 20-40 cm (thesis chapter 6)"
    options = {**TraverseScene.options, "room": "Which room (its seed): chapter 6 learns in one room and tests in another.",
               "clutter": f"Loose objects in the room ({N_OBJECTS}).",
               "size_min": f"Smallest loose-object dimension, metres ({SIZES[0]}).",
               "size_max": f"Largest loose-object dimension, metres ({SIZES[1]})."}

    def __init__(self, config=None, room: int = 0, clutter: int = N_OBJECTS, sizes: tuple[float, float] = SIZES):
        super().__init__(config)
        self.room, self.clutter, self.sizes = int(room), int(clutter), (float(sizes[0]), float(sizes[1]))

    def describe(self) -> dict:
        harder = {} if (self.clutter, self.sizes) == (N_OBJECTS, SIZES) else {"clutter": self.clutter,
                                                                             "sizes": list(self.sizes)}
        return {**super().describe(), "room": self.room, **harder}  # the default room is described as it always was

    def options_from(self, description: dict) -> dict:
        lo, hi = description.get("sizes", SIZES)
        return {**super().options_from(description), "room": description.get("room", 0),
                "clutter": description.get("clutter", N_OBJECTS), "size_min": lo, "size_max": hi}

    def configure(self, grid: int | None = None, layers: int | None = None, room: int | None = None,
                  clutter: int | None = None, size_min: float | None = None,
                  size_max: float | None = None) -> "RoomScene":
        scene = super().configure(grid, layers)
        scene.room = self.room if room is None else int(room)
        scene.clutter = self.clutter if clutter is None else int(clutter)
        lo = self.sizes[0] if size_min is None else float(size_min)
        hi = self.sizes[1] if size_max is None else float(size_max)
        scene.sizes = (lo, hi)
        if scene.room < 0:
            raise DataError(f"a room is a seed, 0 or more; got {scene.room}")
        if not 0 <= scene.clutter <= 80:
            raise DataError(f"a room holds 0-80 loose objects, got {scene.clutter}")
        if not 0.05 <= lo <= hi <= 0.6:
            raise DataError(f"loose objects must satisfy 0.05 <= size-min <= size-max <= 0.6 m, got {lo} and {hi}")
        return scene

    def items(self) -> tuple[Item, ...]:
        """The room's walls and objects in its own frame (its centre)."""
        return room_items(self.room, self.clutter, self.sizes)

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return self.stand(rng)[0]

    def stand(self, rng: np.random.Generator) -> tuple[TraverseLayout, tuple[float, float, float]]:
        """The room seen from a random free place: the layout in the robot's frame, and
        where the robot stands in the room's frame (x, y, yaw)."""
        items = self.items()
        for _ in range(200):
            x, y = rng.uniform(-HALF + 0.4, HALF - 0.4, size=2)
            yaw = float(rng.uniform(0.0, 360.0))
            layout = in_robot_frame(items, float(x), float(y), yaw)
            try:
                check_layout(layout, self.config.world.robot)
            except DataError:
                continue  # on an object, or too near a wall: stand elsewhere
            return layout, (float(x), float(y), yaw)
        raise DataError(f"room {self.room} has no free place for the robot")  # pragma: no cover - 36 m^2, 30 objects
