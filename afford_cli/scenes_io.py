"""Getting a scene to act in: ``--scene NAME --seed S [--objects N]`` or ``--layout FILE``."""

from __future__ import annotations

import numpy as np

from afford_cli.errors import AffordError

__all__ = ["scene_objects", "open_world"]


def scene_objects(scene_name: str, seed: int | None, objects: int, layout: str | None, reachable: bool = False,
                  allow_empty: bool = False):
    """The scene and its objects, from a layout file or drawn from the seed."""
    from afford_cli.commands.explore import make_scene
    from sim.layout import LayoutError, load_layout

    scene = make_scene(scene_name)
    if layout is not None:
        try:
            specs = load_layout(layout)
        except LayoutError as exc:
            raise AffordError(str(exc)) from None
        if not specs and not allow_empty:
            raise AffordError(f"{layout} has no [[object]] entries; the robot needs something to act on")
    else:
        if seed is None:
            raise AffordError("give --layout FILE, or --seed S to draw a random scene")
        rng = np.random.default_rng(np.random.SeedSequence(entropy=seed, spawn_key=(7,)))
        specs = scene.sample_objects(rng, objects, reachable=reachable)
    try:
        scene.check_layout(specs)
    except ValueError as exc:
        raise AffordError(f"{layout or 'the scene'}: {exc}") from None
    return scene, specs


def open_world(scene, specs, seed: int):
    from sim.session import SimWorld

    world = SimWorld(scene, specs, seed)
    if world.perceive().shape[0] == 0:
        raise AffordError("the robot sees no object in this scene")
    return world
