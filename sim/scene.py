"""The Scene protocol: what every registered scene gives the rest of afford.

A scene is a world, a robot and its perception (DESIGN.md section 11). The command line,
the exploration loops and the tests use a scene only through this protocol, so a new
robot adds a scene file (and its robot and perception) and forks nothing else.

What a scene declares
    ``name``, ``summary``; ``schema`` (the :class:`features.FeatureSchema` of its
    entities); ``behaviors`` (:class:`sim.behaviors.Behavior`, each with its target and
    parameters); ``labels``: ``"discovered"`` (effects to cluster) or ``"given"`` (the
    robot's own success reading, named by ``results``); ``outcomes``: the names of the
    ground-truth outcomes its worlds report (for reports only; empty if none); ``loop``: ``"play"`` (Algorithm 5:
    one object, behaviours until it stops changing) or ``"scan"`` (Algorithm 1: one
    environment, scanned once, every behaviour from the same start in a rebuilt world);
    ``options``: the scene-specific settings a command may pass (name -> help text);
    ``sample_options``: the keywords :meth:`sample` takes beyond the generator.

What a scene does
    ``configure(**options)`` a scene with those settings (ValueError for a bad value);
    ``options_from(describe())`` the options that configure a scene so described (to
    rebuild, from an artefact's manifest, the scene it was explored in);
    ``sample(rng, **kw)`` a random layout; ``parse_layout(text, source)``,
    ``layout_toml(layout)``, ``layout_json(layout)`` and ``check_layout(layout)`` for
    layout files and reports;
    ``build(layout, rng)`` a fresh world; ``describe()`` its settings as plain data.

What a world does
    ``perceive()`` the entities, ``(k, d)`` (one row for a scan scene's whole
    environment); ``truth_row()`` (scan scenes) ground truth for one interaction.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Protocol, runtime_checkable

import numpy as np

from afford.features.errors import DataError
from afford.sim.layout import read_layout_file

__all__ = ["Scene", "SceneOptionError", "load_layout_file", "LOOPS", "LABEL_SOURCES"]

LOOPS = ("play", "scan")
LABEL_SOURCES = ("discovered", "given")


class SceneOptionError(DataError):
    """An option that does not apply to a scene (a usage error)."""


@runtime_checkable
class Scene(Protocol):
    name: str
    summary: str
    behaviors: tuple
    labels: str
    results: tuple[str, ...]
    outcomes: tuple[str, ...]
    loop: str
    options: dict[str, str]
    sample_options: tuple[str, ...]

    @property
    def schema(self): ...

    def describe(self) -> dict: ...

    def configure(self, **options: Any) -> "Scene": ...

    def options_from(self, description: dict) -> dict[str, Any]: ...

    def sample(self, rng: np.random.Generator, **kw: Any) -> Any: ...

    def parse_layout(self, text: str, source: str = "layout") -> Any: ...

    def layout_toml(self, layout: Any) -> str: ...

    def layout_json(self, layout: Any) -> Any: ...

    def check_layout(self, layout: Any) -> None: ...

    def build(self, layout: Any, rng: np.random.Generator) -> Any: ...


def load_layout_file(scene: Scene, path: str | Path):
    """Read and parse a layout file for ``scene``; every mistake is one LayoutError sentence.

    A layout may name the scene it was written for (``scene = "traverse"`` at its top); one
    written for a scene whose layouts mean something else (another frame: the table's top
    against the mobile robot's own) is refused. A layout that names none is read as the
    scene's own."""
    import tomllib

    from afford.sim.layout import LayoutError
    from afford.sim.registry import SceneNotFound, get_scene

    text = read_layout_file(path)
    try:
        declared = tomllib.loads(text).get("scene")
    except tomllib.TOMLDecodeError:
        declared = None  # the scene's parser says what is wrong with it
    if declared is not None:
        if not isinstance(declared, str):
            raise LayoutError(f"{path}: scene must be a scene's name, such as \"{scene.name}\"")
        try:
            written = get_scene(declared)
        except SceneNotFound:
            raise LayoutError(f"{path} is a layout of scene {declared!r}, which this afford does not have") from None
        if getattr(written, "layout_format", declared) != getattr(scene, "layout_format", scene.name):
            raise LayoutError(f"{path} is a layout of scene {declared!r}; scene {scene.name!r} reads layouts "
                              "in another frame, so it cannot use it")
    return scene.parse_layout(text, str(path))


def check_options(scene: Scene, given: dict[str, Any], kind: str = "option") -> None:
    """Refuse, in one sentence, options this scene does not have."""
    for name, value in given.items():
        if value is not None and name not in scene.options and name not in scene.sample_options:
            flag = "--" + name.replace("_", "-")
            raise SceneOptionError(f"{flag} does not apply to scene {scene.name!r}")
