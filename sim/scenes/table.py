"""``table``: one robot hand, a table, objects to push and lift (thesis chapter 8).

What the robot has
    A two-finger hand on a gantry arm whose reach is a disc of 1.0 m about its base
    (``sim.hand``), and a range camera to its right, behind and above the table
    (176 x 144 rays 0.23 deg apart, 3 mm range noise, ``sim.camera``).

The world
    A table 100 cm wide and 70 cm deep, its near edge 40 cm in front of the robot, its top
    75 cm above the floor; about a fifth of it lies beyond the arm's reach.

What is randomised (per episode, from the episode's seed)
    One object: box, upright cylinder, lying cylinder or sphere (equally likely); each
    dimension uniform in ``size_range`` (default 8-40 cm); position uniform over the part
    of the table where the object fits; yaw uniform in [0, 360). Mass follows from the
    volume at 300 kg/m^3. Range noise.

What the behaviours do (``sim.behaviors``)
    ``push-forward``, ``push-left``, ``push-right``, ``lift``, aimed at the perceived object.

What ground truth is kept (for reports and evaluation, never for learning)
    Shape and size, poses before and after, in hand before and after, reachable (the
    approach point was within reach and the hand moved), contact (the hand touched the
    object), and one outcome label: ``fell``, ``left-view``, ``lifted``, ``dragged`` or
    ``no-change`` (first that applies).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from dataclasses import replace

from afford.features import object_schema
from afford.features.errors import DataError
from afford.features.interactions import OUTCOMES
from afford.sim.behaviors import TABLE_BEHAVIORS
from afford.sim.camera import RangeCamera
from afford.sim.layout import layout_toml, parse_layout
from afford.sim.objects import SHAPES, SOLID_SHAPES, ObjectSpec
from afford.sim.registry import register_scene
from afford.sim.world import TableConfig, TableWorld

__all__ = ["TableScene", "TableSceneConfig"]


@dataclass(frozen=True)
class TableSceneConfig:
    """What is randomised, and the world's fixed settings."""

    size_range: tuple[float, float] = (0.08, 0.40)
    """Each object dimension is uniform in this range (metres)."""
    shapes: tuple[str, ...] = SOLID_SHAPES
    """Shapes to draw from, equally likely."""
    world: TableConfig = field(default_factory=TableConfig)
    """Table, hand, camera and physics settings."""
    max_steps: int = 10
    """Most behaviours per exploration episode (Algorithm 5 stops earlier once the object stops changing)."""

    def __post_init__(self) -> None:
        lo, hi = self.size_range
        if not (0.02 <= lo <= hi <= 0.6):
            raise DataError(f"object sizes must satisfy 0.02 <= min <= max <= 0.6 m, got {lo} and {hi}")
        if self.max_steps < 1:
            raise DataError(f"an episode needs at least one step, got max_steps {self.max_steps}")
        for s in self.shapes:
            if s not in SHAPES:
                raise DataError(f"unknown shape {s!r}; known shapes: {', '.join(SHAPES)}")


@register_scene("table")
class TableScene:
    """The chapter 8 tabletop (see the module docstring for its task sheet)."""

    name = "table"
    layout_format = "table"  # positions on the table top, x frontal, y lateral
    behaviors = TABLE_BEHAVIORS
    summary = "a hand pushes and lifts one random object on a table (thesis chapter 8)"
    labels = "discovered"
    results: tuple[str, ...] = ()
    outcomes = OUTCOMES
    loop = "play"
    options = {
        "size_min": "Smallest object dimension, metres (0.02-0.6).",
        "size_max": "Largest object dimension, metres (0.02-0.6).",
        "max_steps": "Most behaviours per episode.",
    }
    sample_options = ("objects", "reachable")

    def __init__(self, config: TableSceneConfig | None = None):
        self.config = config or TableSceneConfig()
        self._camera: RangeCamera | None = None

    @property
    def schema(self):
        return object_schema()

    def describe(self) -> dict:
        """The configuration as plain data, stored in every artefact."""
        d = asdict(self.config)
        d["name"] = self.name
        return d

    def options_from(self, description: dict) -> dict:
        lo, hi = description.get("size_range", self.config.size_range)
        return {"size_min": lo, "size_max": hi, "max_steps": description.get("max_steps", self.config.max_steps)}

    def configure(self, size_min: float | None = None, size_max: float | None = None,
                  max_steps: int | None = None) -> "TableScene":
        """This scene with other object sizes or episode length (ValueError, one sentence, if bad)."""
        c = self.config
        lo = c.size_range[0] if size_min is None else float(size_min)
        hi = c.size_range[1] if size_max is None else float(size_max)
        if lo > hi:
            raise DataError(f"the smallest object size ({lo}) is larger than the largest ({hi})")
        return type(self)(replace(c, size_range=(lo, hi), max_steps=c.max_steps if max_steps is None else int(max_steps)))

    def sample(self, rng: np.random.Generator, objects: int = 1, reachable: bool = False) -> list[ObjectSpec]:
        """A random layout: ``objects`` objects apart on the table (within reach if asked)."""
        if objects == 1 and not reachable:
            return [self.sample_object(rng)]
        return self.sample_objects(rng, objects, reachable=reachable)

    def parse_layout(self, text: str, source: str = "layout") -> list[ObjectSpec]:
        return parse_layout(text, source)

    def layout_toml(self, layout: list[ObjectSpec]) -> str:
        return layout_toml(layout)

    def layout_json(self, layout: list[ObjectSpec]) -> list[dict]:
        return [s.to_dict() for s in layout]

    def sample_object(self, rng: np.random.Generator) -> ObjectSpec:
        c = self.config
        shape = c.shapes[int(rng.integers(len(c.shapes)))]
        lo, hi = c.size_range
        n = {"box": 3, "cylinder": 2, "lying-cylinder": 2, "sphere": 1}[shape]
        size = tuple(float(round(v, 4)) for v in rng.uniform(lo, hi, size=n))
        yaw = float(rng.uniform(0.0, 360.0))
        # Half extents of the yawed footprint, so the object starts wholly on the table.
        hx, hy = ObjectSpec(shape, size, (0.0, 0.0), yaw).half_footprint
        w = c.world
        x = float(rng.uniform(w.table_near + hx, max(w.table_near + hx, w.table_far - hx)))
        y = float(rng.uniform(-w.table_width / 2 + hy, max(-w.table_width / 2 + hy, w.table_width / 2 - hy)))
        return ObjectSpec(shape, size, (round(x, 4), round(y, 4)), round(yaw, 3))

    def within_reach(self, spec: ObjectSpec, margin: float = 0.05) -> bool:
        """Is the object's centre inside the arm's reach (less ``margin``)?"""
        hand = self.config.world.hand
        return math.dist(spec.position, hand.shoulder) <= hand.reach - margin

    def sample_objects(self, rng: np.random.Generator, n: int = 1, min_gap: float = 0.05,
                       restarts: int = 50, tries: int = 50, reachable: bool = False) -> list[ObjectSpec]:
        """``n`` random objects whose footprints keep ``min_gap`` apart (all within reach if asked)."""
        for _ in range(restarts):
            out: list[ObjectSpec] = []
            for _ in range(tries):
                cand = self.sample_object(rng)
                if reachable and not self.within_reach(cand):
                    continue
                if all(math.dist(cand.position, o.position) >= cand.footprint_radius + o.footprint_radius + min_gap
                       for o in out):
                    out.append(cand)
                    if len(out) == n:
                        return out
        raise DataError(f"could not place {n} objects apart on the table; try fewer or smaller objects")

    def check_layout(self, objects: list[ObjectSpec]) -> None:
        """Raise ValueError (one sentence) if a layout's objects do not stand on this table."""
        w = self.config.world
        for i, o in enumerate(objects):
            x, y = o.position
            if not (w.table_near <= x <= w.table_far and -w.table_width / 2 <= y <= w.table_width / 2):
                raise DataError(f"object {i} at ({x}, {y}) is not on the table "
                                 f"(x {w.table_near}..{w.table_far}, y {-w.table_width / 2}..{w.table_width / 2})")
            hx, hy = o.half_footprint
            if (x - hx < w.table_near - 0.01 or x + hx > w.table_far + 0.01
                    or abs(y) + hy > w.table_width / 2 + 0.01) and not o.held:
                raise DataError(f"object {i} at ({x}, {y}) hangs over the table's edge; move it inwards")
        for i, a in enumerate(objects):
            for j in range(i + 1, len(objects)):
                b = objects[j]
                if math.dist(a.position, b.position) < 0.5 * (min(a.extents[:2]) + min(b.extents[:2])):
                    raise DataError(f"objects {i} and {j} overlap")

    def build(self, objects: list[ObjectSpec], rng: np.random.Generator) -> TableWorld:
        """A fresh world with these objects (one per episode: a reused scene carries history)."""
        if self._camera is None:
            self._camera = RangeCamera(self.config.world.camera)
        return TableWorld(self.config.world, objects, rng, camera=self._camera)
