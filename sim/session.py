"""A scene a planner or a predictor can drive: perceive, act, perceive again.

``SimWorld`` implements the small ``World`` protocol that ``plan`` talks to (``perceive``
and ``act``), so that closed-loop execution never imports the simulator. It keeps one
physics world for the whole session (the objects stay where the last behaviour left them)
and the last step's ground truth for reports.
"""

from __future__ import annotations

import numpy as np

from sim.explore import Step, interact
from sim.objects import ObjectSpec

__all__ = ["SimWorld"]


class SimWorld:
    """One scene with given objects, driven behaviour by behaviour."""

    def __init__(self, scene, objects: list[ObjectSpec], seed: int = 0):
        scene.check_layout(objects)
        self.scene = scene
        self.objects = list(objects)
        self.rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(2**31,)))
        self.world = scene.build(self.objects, self.rng)
        self._behaviors = {b.name: b for b in scene.behaviors}
        self.state = self.world.perceive()
        self.history: list[Step] = []

    @property
    def behavior_names(self) -> list[str]:
        return list(self._behaviors)

    def perceive(self) -> np.ndarray:
        """The tracked objects' feature vectors (k, d); vanished ones have visibility 0."""
        return self.state.copy()

    @property
    def last_executed(self) -> bool:
        """Did the arm carry out the last behaviour? (No: its target lay beyond reach.)"""
        return self.history[-1].executed if self.history else True

    def act(self, behavior: str, target: int, alpha: np.ndarray | None = None) -> np.ndarray:
        """Run ``behavior`` on tracked object ``target``; return what is perceived after."""
        if behavior not in self._behaviors:
            raise ValueError(f"unknown behaviour {behavior!r}; this scene has {', '.join(self._behaviors)}")
        if not 0 <= target < self.state.shape[0]:
            raise ValueError(f"there is no object {target}; the robot sees {self.state.shape[0]}")
        step = interact(self.world, self._behaviors[behavior], target, alpha, before=self.state)
        self.history.append(step)
        self.state = step.after
        return self.perceive()
