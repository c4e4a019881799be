"""Shared fixtures: the table scene and a one-call "put these objects there and act"."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features import OUTCOMES
from afford.sim.explore import Step, interact
from afford.sim.objects import ObjectSpec
from afford.sim.registry import get_scene


@pytest.fixture(scope="session")
def pipeline(tmp_path_factory):
    """A small table pipeline, made once: train/test interactions, effects, features, model."""
    from typer.testing import CliRunner

    from afford.app import app

    runner = CliRunner()

    def ok(args):
        result = runner.invoke(app, args)
        assert result.exit_code == 0, (args, result.output)

    d = tmp_path_factory.mktemp("learn")
    ok(["explore", "--interactions", "480", "--seed", "4", "--workers", "2", "-o", str(d / "train.afford")])
    ok(["explore", "--interactions", "160", "--seed", "5", "--workers", "2", "-o", str(d / "test.afford")])
    ok(["cluster", str(d / "train.afford"), "-o", str(d / "effects.afford"), "--seed", "1"])
    ok(["select-features", str(d / "effects.afford"), "-o", str(d / "features.afford"), "--top", "12"])
    ok(["train", str(d / "features.afford"), "-o", str(d / "model.afford")])
    return d


@pytest.fixture(scope="session")
def traverse_learned(tmp_path_factory):
    """A small traverse pipeline, made once: 36 training and 8 test environments, features, model."""
    from tests.clitools import ok

    d = tmp_path_factory.mktemp("traverse")
    ok(["explore", "--scene", "traverse", "--episodes", "36", "--seed", "5", "--workers", "2", "-o", str(d / "train.afford")])
    ok(["explore", "--scene", "traverse", "--episodes", "8", "--seed", "6", "-o", str(d / "test.afford")])
    ok(["select-features", str(d / "train.afford"), "-o", str(d / "features.afford")])
    ok(["train", str(d / "features.afford"), "-o", str(d / "model.afford")])
    return d


@pytest.fixture(scope="session")
def grasp_learned(tmp_path_factory):
    """A small grasp pipeline (chapter 9: behaviours with a parameter), made once."""
    from tests.clitools import ok

    d = tmp_path_factory.mktemp("grasp")
    ok(["explore", "--scene", "grasp", "--interactions", "240", "--seed", "3", "--workers", "2", "-o", str(d / "train.afford")])
    ok(["cluster", str(d / "train.afford"), "-o", str(d / "effects.afford")])
    ok(["select-features", str(d / "effects.afford"), "-o", str(d / "features.afford")])
    ok(["train", str(d / "features.afford"), "-o", str(d / "model.afford")])
    return d


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
