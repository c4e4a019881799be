"""Getting a scene to act in: ``--scene NAME --seed S [drawing options]`` or ``--layout FILE``."""

from __future__ import annotations

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
    """The scene and a layout of it, from a layout file or drawn from the seed
    (:func:`afford.api.scene_and_layout`, its errors as the command line reports them).

    ``drawn`` holds the drawing options a command offers (``objects``, ``reachable``);
    one the scene does not take is a usage error, unless it was left unset.
    """
    import typer

    from afford.api import scene_and_layout
    from afford.sim.scene import SceneOptionError

    if layout is None and seed is None:
        raise AffordError("give --layout FILE, or --seed S to draw a random scene")
    try:
        return scene_and_layout(make_scene(scene_name), seed, layout, allow_empty=allow_empty, **drawn)
    except SceneOptionError as exc:
        raise typer.BadParameter(str(exc)) from None
    except DataError as exc:
        raise AffordError(str(exc)) from None


def open_world(scene, specs, seed: int):
    from afford.sim.session import SimWorld

    world = SimWorld(scene, specs, seed)
    if world.perceive().shape[0] == 0:
        raise AffordError("the robot sees no object in this scene")
    return world
