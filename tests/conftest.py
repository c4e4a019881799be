"""Shared fixtures: the table scene and a one-call "put these objects there and act"."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features import OUTCOMES
from afford.sim.explore import Step, interact
from afford.sim.objects import ObjectSpec
from afford.sim.registry import get_scene


@pytest.fixture(scope="session")
def table():
    return get_scene("table")()


def behaviour(scene, name: str):
    return next(b for b in scene.behaviors if b.name == name)


def act(scene, specs: list[ObjectSpec], name: str, seed: int = 0, target: int = 0) -> Step:
    """Build a fresh world with ``specs``, perceive, run behaviour ``name`` on ``target``."""
    world = scene.build(specs, np.random.default_rng(seed))
    return interact(world, behaviour(scene, name), target)


def label(step: Step, i: int = 0) -> str:
    return OUTCOMES[step.outcomes[i]]
