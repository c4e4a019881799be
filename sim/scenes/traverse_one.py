"""``traverse-one``: one object of chosen shapes in front of the mobile robot (thesis 5.6.4.1).

The thesis asked whether what the robot learned carries over to objects it never met: it
trained on environments holding one object of a subset of the four shapes, and tested on
environments holding one object of each shape alone (Table 5.3). The ``shapes`` option
is that subset; train with some, test with another.

What the robot has
    The traverse scenes' robot and perception (``sim.robots.mobile``, ``sim.scanner``,
    ``features.grid``).

What is randomised (per episode)
    Exactly one loose object, its shape drawn from ``shapes`` (default all four: box,
    cylinder, lying-cylinder, sphere), every dimension 10-40 cm, its centre 0.35-0.95 m ahead
    and up to 0.3 m to either side (in the path of go-forward's 70 cm, or beside it), any yaw
    (``sim.traverse.sample_clutter``). Range noise.

What the behaviours do (``sim.moves``)
    The seven moves, each from the same start; result: the robot's odometry. Whether the
    object blocks, rolls or is shoved is PhysX's: the shape is never read.

What ground truth is kept (reports only)
    As ``traverse``.
"""

from __future__ import annotations

import numpy as np

from afford.features.errors import DataError
from afford.sim.moves import TraverseScene
from afford.sim.objects import SOLID_SHAPES
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, sample_clutter

__all__ = ["OneObjectScene", "parse_shapes"]


def parse_shapes(value) -> tuple[str, ...]:
    """``"box,sphere"`` (or a sequence of names) as a tuple of shapes, in the library's order."""
    names = [v.strip() for v in value.split(",")] if isinstance(value, str) else [str(v) for v in value]
    names = [n for n in names if n]
    if not names:
        raise DataError(f"give at least one shape: {', '.join(SOLID_SHAPES)}")
    unknown = [n for n in names if n not in SOLID_SHAPES]
    if unknown:
        raise DataError(f"unknown shape {unknown[0]!r}; the shapes are {', '.join(SOLID_SHAPES)}")
    return tuple(s for s in SOLID_SHAPES if s in names)


@register_scene("traverse-one")
class OneObjectScene(TraverseScene):
    """One object of the chosen shapes in front of the mobile robot (see the module docstring)."""

    summary = "one object of chosen shapes in front of the mobile robot: do affordances carry to novel objects? (thesis 5.6.4.1)"
    options = {**TraverseScene.options, "shapes": "The shapes the one object is drawn from (comma-separated: box, cylinder, lying-cylinder, sphere)."}

    def __init__(self, config=None, shapes: tuple[str, ...] = SOLID_SHAPES):
        super().__init__(config)
        self.shapes = parse_shapes(shapes)

    def describe(self) -> dict:
        return {**super().describe(), "shapes": list(self.shapes)}

    def options_from(self, description: dict) -> dict:
        return {**super().options_from(description), "shapes": tuple(description.get("shapes", SOLID_SHAPES))}

    def configure(self, grid: int | None = None, layers: int | None = None, shapes=None) -> "OneObjectScene":
        scene = super().configure(grid, layers)
        scene.shapes = self.shapes if shapes is None else parse_shapes(shapes)
        return scene

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return sample_clutter(rng, min_objects=1, max_objects=1, x_range=(0.35, 0.95), y_range=(-0.3, 0.3),
                              shapes=self.shapes, robot=self.config.world.robot)
