"""Furniture built from boxes: the complex objects of thesis 5.6.4.2, never met in training.

The thesis tested its robot, trained among simple objects, on "complex real-world objects":
a wooden table with 5.5 cm legs that the robot can sometimes drive under, an iron table with
3.5 cm legs whose bars connecting the legs stop it, and a chair with 4 cm legs, a seat and a
backrest with rails. Here each is a set of boxes, fixed where they stand (kinematic):
a real table of 15-30 kg on a floor of friction 0.5 needs 75-150 N to slide, and the
robot's drive pushes with about 35 N, so a table that does not move is the same world,
simpler to build. What passes under, between the legs or not at all is PhysX's business.

Each ``sample_*`` draws one piece's dimensions and its pose in front of the robot; ``place``
turns a piece's boxes, given in its own frame, into :class:`sim.traverse.Item` in the
robot's start frame. Every piece is a tuple of items, so a room can hold many.
"""

from __future__ import annotations

import math

import numpy as np

from afford.sim.traverse import Item

__all__ = ["KINDS", "place", "piece", "footprint", "wooden_table", "iron_table", "chair", "sample_furniture"]

#: The kinds of furniture, as the thesis's Figure 5.8 shows them.
KINDS = ("wooden-table", "iron-table", "chair")

Box = tuple[tuple[float, float, float], tuple[float, float], float]
"""A box in a piece's own frame: (size x, y, z), (centre x, y), bottom z."""


def _r(v: float) -> float:
    return float(round(float(v), 4))


def _split(box: Box, most: float = 1.0) -> list[Box]:
    """A box longer than ``most`` along x or y (an object's largest size) as equal pieces side by side."""
    (sx, sy, sz), (cx, cy), bottom = box
    nx, ny = math.ceil(sx / most - 1e-9), math.ceil(sy / most - 1e-9)
    return [((sx / nx, sy / ny, sz), (cx - sx / 2 + sx / nx * (i + 0.5), cy - sy / 2 + sy / ny * (j + 0.5)), bottom)
            for i in range(nx) for j in range(ny)]


def place(boxes: list[Box], x: float, y: float, yaw: float) -> tuple[Item, ...]:
    """The piece's boxes, turned by ``yaw`` degrees and centred at (x, y), as fixed items
    (a box over 1 m long as pieces: one object is at most 1 m)."""
    c, s = math.cos(math.radians(yaw)), math.sin(math.radians(yaw))
    boxes = [piece for box in boxes for piece in _split(box)]
    return tuple(Item("box", tuple(_r(v) for v in size), (_r(x + c * bx - s * by), _r(y + s * bx + c * by)),
                      _r(yaw % 360.0), z=_r(bottom), fixed=True)
                 for size, (bx, by), bottom in boxes)


def _legs(length: float, width: float, leg: float, height: float, inset: float = 0.03) -> list[Box]:
    hx, hy = length / 2 - inset - leg / 2, width / 2 - inset - leg / 2
    return [((leg, leg, height), (sx * hx, sy * hy), 0.0) for sx in (-1, 1) for sy in (-1, 1)]


def wooden_table(length: float, width: float, height: float, leg: float = 0.055, top: float = 0.03) -> list[Box]:
    """Four legs and a top whose upper face is ``height`` above the floor."""
    return _legs(length, width, leg, height - top) + [((length, width, top), (0.0, 0.0), height - top)]


def iron_table(length: float, width: float, height: float, bar: float, leg: float = 0.035,
               top: float = 0.02) -> list[Box]:
    """Four thin legs, a top, and bars joining the legs on all four sides, their bottom ``bar`` above the floor."""
    boxes = _legs(length, width, leg, height - top) + [((length, width, top), (0.0, 0.0), height - top)]
    hx, hy = length / 2 - 0.03 - leg / 2, width / 2 - 0.03 - leg / 2
    boxes += [((2 * hx, leg, leg), (0.0, sy * hy), bar) for sy in (-1, 1)]
    boxes += [((leg, 2 * hy, leg), (sx * hx, 0.0), bar) for sx in (-1, 1)]
    return boxes


def chair(seat: float = 0.42, seat_height: float = 0.45, back: float = 0.90, leg: float = 0.04) -> list[Box]:
    """Four legs, a seat, and a backrest: two posts at the back joined by two rails."""
    t = 0.04
    boxes = _legs(seat, seat, leg, seat_height - t, inset=0.0) + [((seat, seat, t), (0.0, 0.0), seat_height - t)]
    bx = -(seat / 2 - leg / 2)
    boxes += [((leg, leg, back - seat_height), (bx, sy * (seat / 2 - leg / 2)), seat_height) for sy in (-1, 1)]
    boxes += [((leg, seat, t), (bx, 0.0), h) for h in (seat_height + 0.20, back - t)]
    return boxes


def piece(rng: np.random.Generator, kind: str) -> list[Box]:
    """One piece of ``kind`` of random dimensions, in its own frame (see :func:`sample_furniture`)."""
    if kind == "wooden-table":
        return wooden_table(rng.uniform(0.9, 1.4), rng.uniform(0.6, 0.9), rng.uniform(0.35, 0.80))
    if kind == "iron-table":
        height = rng.uniform(0.55, 0.80)
        return iron_table(rng.uniform(1.0, 1.4), rng.uniform(0.6, 0.8), height, rng.uniform(0.05, height - 0.06))
    if kind == "chair":
        return chair()
    raise ValueError(f"unknown furniture {kind!r}; the kinds are {', '.join(KINDS)}")


def footprint(boxes: list[Box], x: float, y: float, yaw: float):
    """The piece's bounding rectangle on the floor, posed: ((x, y), (half x, half y), yaw)."""
    hx = max(abs(bx) + sx / 2 for (sx, _, _), (bx, _), _ in boxes)
    hy = max(abs(by) + sy / 2 for (_, sy, _), (_, by), _ in boxes)
    return (float(x), float(y)), (float(hx), float(hy)), float(yaw)


#: Where each kind stands in front of the robot in ``traverse-furniture``: x and y ranges.
_IN_FRONT = {"wooden-table": ((0.5, 1.3), (-0.4, 0.4)), "iron-table": ((0.5, 1.3), (-0.6, 0.6)),
             "chair": ((0.4, 1.2), (-0.55, 0.55))}


def sample_furniture(rng: np.random.Generator, kind: str) -> tuple[Item, ...]:
    """One piece of ``kind`` of random dimensions (within the thesis's descriptions) and pose.

    The wooden table is 0.9-1.4 x 0.6-0.9 m and 0.35-0.80 m high (so it can sometimes be
    driven under), within 0.5-1.3 m ahead and 0.4 m to either side; the iron table 1.0-1.4 x
    0.6-0.8 m, 0.55-0.80 m high, its bars from 0.05 m above the floor to just under the top,
    shifted up to 0.6 m to either side; the chair fixed in shape, 0.4-1.2 m ahead and 0.55 m
    to either side. Every piece is turned any way (0-360 degrees).
    """
    boxes = piece(rng, kind)
    (x0, x1), (y0, y1) = _IN_FRONT[kind]
    x, y = rng.uniform(x0, x1), rng.uniform(y0, y1)
    return place(boxes, float(x), float(y), float(rng.uniform(0.0, 360.0)))
