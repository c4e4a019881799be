"""Layout files: a scene pinned exactly, in TOML (DESIGN.md section 4).

.. code-block:: toml

    [[object]]
    shape = "box"               # box | cylinder | lying-cylinder | sphere
    size = [0.12, 0.12, 0.12]   # metres: box edges, [diameter, length], or [diameter]
    position = [0.70, 0.10]     # x frontal, y lateral (left +), on the table top
    yaw = 30.0                  # degrees
    held = false                # true: starts grasped and lifted by the hand

Every mistake is reported as one sentence naming the file and the object.
"""

from __future__ import annotations

import tomllib
from pathlib import Path

from afford.features.errors import DataError
from afford.sim.objects import SHAPES, ObjectSpec

__all__ = ["LayoutError", "parse_layout", "load_layout", "layout_toml", "read_layout_file"]

_KEYS = {"shape", "size", "position", "yaw", "held"}


class LayoutError(DataError):
    """A layout file that cannot be used."""


def _numbers(value, what: str, where: str) -> tuple[float, ...]:
    if not isinstance(value, list) or not all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
        raise LayoutError(f"{where}: {what} must be a list of numbers")
    return tuple(float(v) for v in value)


def parse_layout(text: str, source: str = "layout") -> list[ObjectSpec]:
    """Objects of a layout given as TOML text (an empty layout is an empty table)."""
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise LayoutError(f"{source} is not valid TOML ({exc})") from None
    unknown_top = set(doc) - {"object", "scene"}  # the scene it names is checked when the file is read
    if unknown_top:
        raise LayoutError(f"{source}: unknown table {sorted(unknown_top)[0]!r}; a layout holds [[object]] entries")
    items = doc.get("object", [])
    if not isinstance(items, list):
        raise LayoutError(f"{source}: 'object' must be a list of [[object]] tables")
    specs = []
    for i, item in enumerate(items):
        where = f"{source}, object {i}"
        if not isinstance(item, dict):
            raise LayoutError(f"{where}: each object must be an [[object]] table, not {type(item).__name__}")
        extra = set(item) - _KEYS
        if extra:
            raise LayoutError(f"{where}: unknown key {sorted(extra)[0]!r}; known keys: {', '.join(sorted(_KEYS))}")
        for key in ("shape", "size", "position"):
            if key not in item:
                raise LayoutError(f"{where}: missing {key!r}")
        shape = item["shape"]
        if shape not in SHAPES:
            raise LayoutError(f"{where}: unknown shape {shape!r}; known shapes: {', '.join(SHAPES)}")
        yaw = item.get("yaw", 0.0)
        if not isinstance(yaw, (int, float)) or isinstance(yaw, bool):
            raise LayoutError(f"{where}: yaw must be a number of degrees")
        held = item.get("held", False)
        if not isinstance(held, bool):
            raise LayoutError(f"{where}: held must be true or false")
        size = _numbers(item["size"], "size", where)
        position = _numbers(item["position"], "position", where)
        try:
            specs.append(ObjectSpec(shape, size, position, float(yaw), held))  # type: ignore[arg-type]
        except ValueError as exc:
            raise LayoutError(f"{where}: {exc}") from None
    if sum(s.held for s in specs) > 1:
        raise LayoutError(f"{source}: the hand can hold only one object")
    return specs


def read_layout_file(path: str | Path) -> str:
    """The text of a layout file; a missing, unreadable or non-text file is one LayoutError sentence."""
    if str(path) in ("", "-"):
        raise LayoutError("give a layout file name (layouts are not read from standard input)")
    p = Path(path)
    if not p.exists():
        raise LayoutError(f"layout file {path} does not exist")
    if p.is_dir():
        raise LayoutError(f"layout file {path} is a directory")
    try:
        return p.read_text(encoding="utf-8")
    except UnicodeDecodeError:
        raise LayoutError(f"layout file {path} is not UTF-8 text") from None
    except OSError as exc:
        raise LayoutError(f"cannot read layout file {path} ({exc.strerror})") from None


def load_layout(path: str | Path) -> list[ObjectSpec]:
    """A table layout file's objects."""
    return parse_layout(read_layout_file(path), str(path))


def layout_toml(specs: list[ObjectSpec]) -> str:
    """The TOML text of a layout (the inverse of :func:`parse_layout`)."""
    lines = []
    for s in specs:
        lines += [
            "[[object]]",
            f'shape = "{s.shape}"',
            f"size = [{', '.join(repr(float(v)) for v in s.size)}]",
            f"position = [{', '.join(repr(float(v)) for v in s.position)}]",
            f"yaw = {float(s.yaw)!r}",
            f"held = {'true' if s.held else 'false'}",
            "",
        ]
    return "\n".join(lines)
