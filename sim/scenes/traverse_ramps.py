"""``traverse-ramps``: one ramp, climbable or not by its slope and orientation (thesis 5.6.2.2).

What the robot has
    The mobile robot and scanner of ``traverse`` (``sim.scenes.traverse``).

What is randomised (per episode)
    One static ramp: its toe 0.3-0.9 m ahead and up to 0.5 m to either side, turned -90..90 deg from the robot's heading,
    0.5-1.5 m wide and long, 2-40 deg steep (``sim.traverse.sample_ramp``). Whether the
    robot climbs it is what its wheels' traction and its weight make of the slope.

What the behaviours do
    The seven moves of ``sim.moves``, each from the same start; result: odometry.

What ground truth is kept (reports only)
    As ``traverse``; the robot's tilt at the end.
"""

from __future__ import annotations

import numpy as np

from afford.sim.moves import TraverseScene
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, sample_ramp

__all__ = ["RampScene"]


@register_scene("traverse-ramps")
class RampScene(TraverseScene):
    """One random ramp in front of the mobile robot (see the module docstring)."""

    summary = "a mobile robot learns which ramps it can climb, by slope and orientation (thesis 5.6.2.2)"

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return sample_ramp(rng)
