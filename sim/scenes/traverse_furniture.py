"""``traverse-furniture``: a table or a chair in front of the mobile robot (thesis 5.6.4.2).

A test scene: the robot learns among simple objects (``traverse``) and is asked about
furniture it never met, as the thesis did with a wooden table, an iron table and a chair.

What the robot has
    The traverse scenes' robot and perception (``sim.robots.mobile``, ``sim.scanner``,
    ``features.grid``).

What is randomised (per episode)
    One piece of furniture of the kind the ``furniture`` option names (``sim.furniture``):
    a wooden table (5.5 cm legs, 0.35-0.80 m high: some can be driven under), an iron table
    (3.5 cm legs, bars joining them 0.05 m above the floor up to just under its top) or a
    chair (4 cm legs, a seat at 0.45 m, a backrest with rails), of random size where the
    thesis varied it, at a random place in front of the robot and turned any way. Every
    piece is fixed boxes. Range noise.

What the behaviours do (``sim.moves``)
    The seven moves, each from the same start; result: the robot's odometry. Whether it
    drives under a table, between its legs or into its bars is PhysX's.

What ground truth is kept (reports only)
    As ``traverse``.
"""

from __future__ import annotations

import numpy as np

from afford.features.errors import DataError
from afford.sim.furniture import KINDS, sample_furniture
from afford.sim.moves import TraverseScene
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, check_layout

__all__ = ["FurnitureScene"]


@register_scene("traverse-furniture")
class FurnitureScene(TraverseScene):
    """One table or chair in front of the mobile robot (see the module docstring)."""

    summary = "a table or a chair the robot never met, in front of it: do affordances carry over? (thesis 5.6.4.2)"
    options = {**TraverseScene.options, "furniture": f"Which piece: {', '.join(KINDS)}."}

    def __init__(self, config=None, furniture: str = KINDS[0]):
        super().__init__(config)
        self.furniture = self._kind(furniture)

    @staticmethod
    def _kind(kind: str) -> str:
        if kind not in KINDS:
            raise DataError(f"unknown furniture {kind!r}; the kinds are {', '.join(KINDS)}")
        return kind

    def describe(self) -> dict:
        return {**super().describe(), "furniture": self.furniture}

    def options_from(self, description: dict) -> dict:
        return {**super().options_from(description), "furniture": description.get("furniture", KINDS[0])}

    def configure(self, grid: int | None = None, layers: int | None = None, furniture: str | None = None) -> "FurnitureScene":
        scene = super().configure(grid, layers)
        scene.furniture = self.furniture if furniture is None else self._kind(furniture)
        return scene

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        for _ in range(100):
            layout = TraverseLayout(items=sample_furniture(rng, self.furniture))
            try:
                check_layout(layout, self.config.world.robot)
            except DataError:
                continue  # a leg where the robot stands: put the piece elsewhere
            return layout
        raise DataError(f"no place for the {self.furniture} in front of the robot")  # pragma: no cover
