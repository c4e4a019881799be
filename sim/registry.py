"""Scenes register by name (``@register_scene("table")``), one scene per file.

Importing ``sim.scenes`` registers every scene in it. ``get_scene`` raises
:class:`SceneNotFound` with the list of known names.
"""

from __future__ import annotations

from typing import Callable, TypeVar
from afford.features.errors import DataError, NameNotFound

__all__ = ["register_scene", "get_scene", "scene_names", "make_scene", "SceneNotFound"]

_SCENES: dict[str, type] = {}
T = TypeVar("T", bound=type)


class SceneNotFound(NameNotFound):
    """No scene is registered by that name."""


def register_scene(name: str) -> Callable[[T], T]:
    def wrap(cls: T) -> T:
        if name in _SCENES and _SCENES[name] is not cls:
            raise DataError(f"a scene named {name!r} is registered already")
        cls.name = name  # type: ignore[attr-defined]
        _SCENES[name] = cls
        return cls

    return wrap


def _load() -> None:
    import afford.sim.scenes  # noqa: F401  (registers the scenes)


def scene_names() -> list[str]:
    _load()
    return sorted(_SCENES)


def get_scene(name: str) -> type:
    _load()
    try:
        return _SCENES[name]
    except KeyError:
        raise SceneNotFound(f"unknown scene {name!r}; known scenes: {', '.join(sorted(_SCENES))}") from None


def make_scene(name: str, **options):
    """An instance of the registered scene ``name``, configured with ``options``.

    Options the scene does not have raise :class:`sim.scene.SceneOptionError` (a usage
    error); a bad value raises ValueError; both in one sentence.
    """
    from afford.sim.scene import check_options

    scene = get_scene(name)()
    check_options(scene, options)
    given = {k: v for k, v in options.items() if v is not None and k in scene.options}
    return scene.configure(**given) if given else scene
