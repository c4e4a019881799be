"""Getting a scene to act in: ``--scene NAME --seed S [drawing options]`` or ``--layout FILE``."""

from __future__ import annotations

from afford.errors import AffordError
from afford.features.errors import DataError

__all__ = ["make_scene", "model_scene", "scene_layout", "open_world", "explored_scene", "episode_starts"]


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


def model_scene(model, name: str | None):
    """The scene a command acts in with ``model``: the one named (``--scene``), else the
    model's own, the scene it was explored in, rebuilt with the options it had (a traverse
    model's grid, a table's size range). A scene that perceives otherwise than the model
    is refused in one sentence naming both."""
    own = model.art.manifest.get("scene")
    own = own if isinstance(own, dict) else {}
    own_name = own.get("name")
    if name is None and not isinstance(own_name, str):
        raise AffordError("this model does not say which scene it was learned in; give --scene NAME")
    if name is None or name == own_name:
        sc = explored_scene(own) or make_scene(own_name if name is None else name)
    else:
        sc = make_scene(name)
    if sc.schema != model.schema:
        learned = f" (it was learned in scene {own_name!r})" if isinstance(own_name, str) else ""
        hint = "; leave out --scene to act in the model's own scene" if name is not None else ""
        raise AffordError(f"scene {sc.name!r} perceives {len(sc.schema)} features, the model reads "
                          f"{len(model.schema)}{learned}{hint}")
    return sc


def scene_layout(scene_name, seed: int | None, layout: str | None, allow_empty: bool = False, **drawn):
    """The scene (a name, or a scene such as :func:`model_scene` gives) and a layout of it,
    from a layout file or drawn from the seed (:func:`afford.api.scene_and_layout`, its
    errors as the command line reports them).

    ``drawn`` holds the drawing options a command offers (``objects``, ``reachable``);
    one the scene does not take is a usage error, unless it was left unset.
    """
    import typer

    from afford.api import scene_and_layout
    from afford.sim.scene import SceneOptionError

    if layout is None and seed is None:
        raise AffordError("give --layout FILE, or --seed S to draw a random scene")
    try:
        return scene_and_layout(make_scene(scene_name) if isinstance(scene_name, str) else scene_name, seed, layout, allow_empty=allow_empty, **drawn)
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


def explored_scene(description: dict):
    """The scene an artefact was explored in, rebuilt from its manifest's description, or
    None when this afford has no such scene or builds it otherwise (its description differs)."""
    import json

    from afford.sim.registry import SceneNotFound, get_scene

    try:
        base = get_scene(str(description.get("name")))()
        scene = base.configure(**base.options_from(description))
    except (SceneNotFound, DataError, ValueError, TypeError, KeyError):
        return None
    same = json.loads(json.dumps(scene.describe())) == json.loads(json.dumps(description))
    return scene if same else None


def episode_starts(description: dict, seed: int | None, data, n: int = 6) -> list[dict]:
    """What the robot saw at the start of the first ``n`` episodes of an exploration,
    re-simulated from (seed, episode): per episode its number, the range image, each
    detected object's pixel box, and whether the re-simulated look matches the recorded one
    (the same features). Empty when the scene cannot be rebuilt (see :func:`explored_scene`)."""
    import numpy as np

    from afford.sim.explore import episode_rng

    scene = explored_scene(description)
    if scene is None or seed is None or len(data) == 0:
        return []
    out = []
    for e in sorted(set(int(x) for x in data.episode))[:n]:
        rng = episode_rng(seed, e)
        world = scene.build(scene.sample(rng), rng)
        look = np.asarray(world.perceive(), dtype=np.float32)
        view = world.last_view()
        if view is None:
            continue
        first = int(np.flatnonzero(data.episode == e)[0])
        recorded = data.entities[data.before_index[first]]
        same = look.shape[0] >= 1 and bool(np.array_equal(look[0], recorded))
        out.append({"episode": e, "ranges": view[0], "boxes": view[1], "matches_recording": same})
    return out
