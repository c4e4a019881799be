"""``traverse``: a mobile robot among random objects learns where it can go (thesis 5.6.1).

What the robot has
    A six-wheeled skid-steer base of KURT3D's size (45 x 33 x 47 cm, ``sim.robots.mobile``)
    with wheel encoders and a gyro, and a 3D range scanner on top at its front (720 x 720
    rays over 180 x 165.6 deg, down-scaled to 360 x 360 by taking minima, ``sim.scanner``).
    It perceives the whole environment as grid features (``features.grid``, 3900).

What is randomised (per episode)
    0-12 objects: boxes, upright cylinders, lying cylinders and spheres, every dimension
    10-40 cm, 0.3-2 m ahead and up to 1 m to either side, any yaw, apart from each other
    (``sim.traverse.sample_clutter``). Range noise.

What the behaviours do (``sim.moves``)
    Seven moves: rotate 0, +-20, +-40 or +-60 deg in place, then drive 70 cm. Every move
    starts from the same scanned start in a freshly built world (Algorithm 1). Result:
    the robot's own odometry reading, success or fail. What blocks, what rolls away and
    what is shoved aside is PhysX's business (one density for every object).

What ground truth is kept (reports only)
    The robot's true pose before and after, whether it fell or touched anything, the
    number of objects, and the odometry values behind each result.
"""

from __future__ import annotations

import numpy as np

from afford.sim.moves import TraverseScene
from afford.sim.registry import register_scene
from afford.sim.traverse import TraverseLayout, sample_clutter

__all__ = ["ClutterScene"]


@register_scene("traverse")
class ClutterScene(TraverseScene):
    """Random clutter in front of the mobile robot (see the module docstring)."""

    summary = "a mobile robot among 0-12 random objects learns which moves it can make (thesis 5.6.1)"

    def sample(self, rng: np.random.Generator) -> TraverseLayout:
        return sample_clutter(rng)
