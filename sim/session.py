"""A scene a planner or a predictor can drive: perceive, act, perceive again.

``SimWorld`` implements the small ``World`` protocol that ``plan`` talks to (``perceive``
and ``act``), so that closed-loop execution never imports the simulator. For a scene whose
labels are discovered it keeps one physics world for the whole session (the objects and the
robot stay where the last behaviour left them, so plans chain); for a scene whose labels are
given (chapter 5's trials) every behaviour starts from the same start in a freshly built
world, as in exploration, and the robot keeps its own reading of how each went. It keeps every step's ground truth for reports.
"""

from __future__ import annotations

import numpy as np

from dataclasses import dataclass

from afford.features.errors import DataError
from afford.sim.explore import Step, interact

__all__ = ["SimWorld", "Trial"]


@dataclass(frozen=True)
class Trial:
    """One behaviour run from the scanned start (a scan scene): the robot's reading, and the truth."""

    behavior: str
    executed: bool
    result: int | None
    reading: dict | None
    truth: dict


class SimWorld:
    """One scene with given objects, driven behaviour by behaviour."""

    def __init__(self, scene, layout, seed: int = 0):
        scene.check_layout(layout)
        self.scene = scene
        self.layout = layout
        self.rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(2**31,)))
        self.world = scene.build(self.layout, self.rng)
        self._behaviors = {b.name: b for b in scene.behaviors}
        self.state = np.asarray(self.world.perceive())
        self._start_image = getattr(self.world, "last_image", None)  # kept, drawn only if asked
        self.history: list[Step | Trial] = []

    @property
    def start_view(self):
        """What the robot saw at the start (see ``last_view`` of the scene's world): the range
        image and each object's pixel box, numbered as the objects are; None if unknown."""
        view = getattr(self.world, "last_view", None)
        return view(self._start_image) if view is not None and self._start_image is not None else None

    @property
    def behavior_names(self) -> list[str]:
        return list(self._behaviors)

    def perceive(self) -> np.ndarray:
        """The tracked objects' feature vectors (k, d); vanished ones have visibility 0."""
        return self.state.copy()

    @property
    def last_executed(self) -> bool:
        """Did the arm carry out the last behaviour? (No: its target lay beyond reach.)"""
        return self.history[-1].executed if self.history else True  # Step and Trial both say

    @property
    def last_result(self) -> int | None:
        """The robot's own reading of the last behaviour (scenes whose labels are given)."""
        last = self.history[-1] if self.history else None
        return last.result if isinstance(last, Trial) else None

    def act(self, behavior: str, target: int, alpha: np.ndarray | None = None) -> np.ndarray:
        """Run ``behavior`` on tracked object ``target`` (any, for a behaviour without a
        target); return what is perceived after."""
        if behavior not in self._behaviors:
            raise DataError(f"unknown behaviour {behavior!r}; this scene has {', '.join(self._behaviors)}")
        b = self._behaviors[behavior]
        if self.scene.labels == "given":
            world = self.scene.build(self.layout, self.rng)  # every behaviour from the same start
            execution = b(world, None, alpha)
            self.history.append(Trial(behavior, execution.executed, execution.result, execution.reading,
                                      world.truth_row()))
            return self.perceive()
        if b.target is not None and not 0 <= target < self.state.shape[0]:
            raise DataError(f"there is no object {target}; the robot sees {self.state.shape[0]}")
        step = interact(self.world, self._behaviors[behavior], target, alpha, before=self.state)
        self.history.append(step)
        self.state = step.after
        return self.perceive()
