"""Getting a scene to act in: ``--scene NAME --seed S [drawing options]`` or ``--layout FILE``."""

from __future__ import annotations

import numpy as np

from afford.errors import AffordError
from afford.features.errors import DataError

__all__ = ["make_scene", "scene_layout", "open_world"]


def make_scene(name: str, **options):
    """The registered scene ``name`` with ``options``; unknown names and bad values are one sentence."""
    import typer

    from afford.sim.registry import SceneNotFound, make_scene as make
    from afford.sim.scene import SceneOptionError

    try:
        return make(name, **options)
    except SceneNotFound as exc:
        raise AffordError(str(exc)) from None
    except SceneOptionError as exc:
        raise typer.BadParameter(str(exc)) from None
    except DataError as exc:
        raise AffordError(f"scene {name!r}: {exc}") from None


def scene_layout(scene_name: str, seed: int | None, layout: str | None, allow_empty: bool = False, **drawn):
    """The scene and a layout of it, from a layout file or drawn from the seed.

    ``drawn`` holds the drawing options a command offers (``objects``, ``reachable``);
    one the scene does not take is a usage error, unless it was left unset.
    """
    import typer

    from afford.sim.layout import LayoutError
    from afford.sim.scene import SceneOptionError, check_options, load_layout_file

    scene = make_scene(scene_name)
    given = {k: v for k, v in drawn.items() if v not in (None, False)}
    try:
        check_options(scene, given)
    except SceneOptionError as exc:
        raise typer.BadParameter(str(exc)) from None
    if layout is not None:
        try:
            specs = load_layout_file(scene, layout)
        except LayoutError as exc:
            raise AffordError(str(exc)) from None
        if scene.loop == "play" and not specs and not allow_empty:
            raise AffordError(f"{layout} has no [[object]] entries; the robot needs something to act on")
    else:
        if seed is None:
            raise AffordError("give --layout FILE, or --seed S to draw a random scene")
        rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(7,)))
        try:
            specs = scene.sample(rng, **given)
        except DataError as exc:
            raise AffordError(str(exc)) from None
    try:
        scene.check_layout(specs)
    except DataError as exc:
        raise AffordError(f"{layout or 'the scene'}: {exc}") from None
    return scene, specs


def open_world(scene, specs, seed: int):
    from afford.sim.session import SimWorld

    world = SimWorld(scene, specs, seed)
    if world.perceive().shape[0] == 0:
        raise AffordError("the robot sees no object in this scene")
    return world
