"""``traverse-body``: boxes hanging in front of the robot teach it its own size (thesis 5.6.2.1).

What the robot has
    The mobile robot and scanner of ``traverse`` (``sim.scenes.traverse``).

What is randomised (per episode)
    0-12 boxes of 5-20 cm, fixed in the air anywhere in the cubic metre in front of the
    robot (bottom 0-1 m above the floor), any yaw (``sim.traverse.sample_body``). A box
    below the robot's top in its path stops it; one above, or beside its path, does not.

What the behaviours do
    The seven moves of ``sim.moves``, each from the same start; result: odometry.

What ground truth is kept (reports only)
    As ``traverse``.
"""

from __future__ import annotations

import numpy as np

from afford.sim.moves import TraverseScene
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, sample_body

__all__ = ["BodyScene"]


@register_scene("traverse-body")
class BodyScene(TraverseScene):
    """Hanging boxes in front of the mobile robot (see the module docstring)."""

    summary = "a mobile robot learns its body size from 0-12 boxes hanging in front of it (thesis 5.6.2.1)"

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return sample_body(rng)
