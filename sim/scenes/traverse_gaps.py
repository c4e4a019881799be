"""``traverse-gaps``: one gap in the floor, crossable or not by its width (thesis 5.6.2.3).

What the robot has
    The mobile robot and scanner of ``traverse`` (``sim.scenes.traverse``).

What is randomised (per episode)
    One gap, its near edge 10-100 cm ahead of the robot's front, 5-50 cm wide, turned
    -60..60 deg (``sim.traverse.sample_gap``): the floor is two slabs with a 50 cm deep
    trench between them. Whether the robot's wheels bridge it is physics.

What the behaviours do
    The seven moves of ``sim.moves``, each from the same start; result: odometry.

What ground truth is kept (reports only)
    As ``traverse``; ``fell`` says the robot ended in the trench.
"""

from __future__ import annotations

import numpy as np

from afford.sim.moves import TraverseScene
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, sample_gap

__all__ = ["GapScene"]


@register_scene("traverse-gaps")
class GapScene(TraverseScene):
    """One random gap in front of the mobile robot (see the module docstring)."""

    summary = "a mobile robot learns which gaps it can cross, by width and orientation (thesis 5.6.2.3)"

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return sample_gap(rng)
