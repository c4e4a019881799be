"""afford: a robot learns what its world affords by playing in it, then predicts, plans and
imitates with what it learned (after Ugur's developmental framework).

The Python API (:mod:`afford.api`) is importable from here: ``afford.load``,
``afford.load_interactions``, ``afford.load_labels``, ``afford.load_model``, ``afford.save``,
``afford.explore``, ``afford.world``, ``afford.make_scene``, ``afford.scene_names``,
``afford.parse_goal``, ``afford.to_frame`` (pandas), ``afford.cluster``, ``afford.select_features``, ``afford.train``, ``afford.Model`` and ``afford.AffordError``. They are loaded on first
use, so ``import afford.features`` stays light. The packages: ``afford.sim`` (scenes,
robots, physics), ``afford.features`` (perception), ``afford.learn`` and ``afford.plan``.
"""

from __future__ import annotations

from importlib import import_module

__all__ = [
    "__version__", "AffordError", "Model", "cluster", "explore", "load", "load_interactions", "load_labels",
    "load_model", "make_scene", "navigate", "parse_goal", "save", "scene_names", "select_features", "to_frame", "train", "world",
]


def _version() -> str:
    try:
        from importlib.metadata import version

        return version("afford")
    except Exception:  # pragma: no cover - a source tree that was never installed
        return "0+unknown"


__version__ = _version()


def __getattr__(name: str):
    if name in __all__:
        value = getattr(import_module("afford.api"), name)
        globals()[name] = value
        return value
    raise AttributeError(f"module 'afford' has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
