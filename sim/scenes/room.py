"""``room``: a furnished, walled room for the mobile robot to drive through (thesis 5.6.5).

The thesis drove its robot, trained among simple objects (5.6.1), through "a virtual room
cluttered with office objects of different sizes and types" (Figure 5.10), with the
aggressive and the cautious controller of Figure 5.9 (``afford navigate``).

What the robot has
    The traverse scenes' robot and perception (``sim.robots.mobile``, ``sim.scanner``,
    ``features.grid``).

What is randomised
    Per room (the ``room`` option, a seed; ``afford navigate --seed`` picks it): the walls
    of ``traverse-room`` around a 6 x 6 m floor; two wooden tables (one may be driven
    under), an iron table with bars and three chairs (``sim.furniture``: fixed boxes, kinds
    the robot never met while learning), each at a random place and yaw; and 16 loose
    objects of the training kinds (boxes, upright and lying cylinders, spheres, 20-40 cm)
    apart from the furniture. Per episode: where the robot starts and which way it faces
    (anywhere free, at least 40 cm inside the walls), and range noise.

What the behaviours do (``sim.moves``)
    The seven moves of the traverse scenes, judged by the robot's odometry. Explored, the
    scene runs Algorithm 1 as ``traverse-room`` does; driven by ``afford navigate``, one
    world persists and the robot moves on from wherever its last move left it.

What ground truth is kept (reports only)
    As ``traverse-room``; ``afford navigate`` adds the true path.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np

from afford.sim.furniture import footprint, piece, place
from afford.sim.registry import register_scene
from afford.sim.scenes.traverse_room import HALF, RoomScene, loose_objects, walls
from afford.sim.traverse import Item, _rects_overlap

__all__ = ["FurnishedRoomScene", "furnished_room_items"]

#: The furniture of every room, by kind.
FURNITURE = ("wooden-table", "wooden-table", "iron-table", "chair", "chair", "chair")
N_LOOSE = 16


@lru_cache(maxsize=16)
def furnished_room_items(room: int) -> tuple[Item, ...]:
    """Room ``room``'s walls, furniture and loose objects, in the room's frame (its centre)."""
    rng = np.random.default_rng(np.random.SeedSequence(entropy=int(room), spawn_key=(4,)))
    pieces, taken = [], []
    for kind in FURNITURE:
        boxes = piece(rng, kind)
        while True:
            x, y = rng.uniform(-HALF + 0.8, HALF - 0.8, size=2)
            yaw = float(rng.uniform(0.0, 360.0))
            fp = footprint(boxes, float(x), float(y), yaw)
            if not any(_rects_overlap(fp, t, 0.3) for t in taken):  # room to pass between pieces
                break
        taken.append(fp)
        pieces += place(boxes, float(x), float(y), yaw)
    return walls() + tuple(pieces) + loose_objects(rng, N_LOOSE, tuple(taken))


@register_scene("room")
class FurnishedRoomScene(RoomScene):
    """A walled room of furniture and loose objects (see the module docstring)."""

    options = {k: v for k, v in RoomScene.options.items() if k not in ("clutter", "size_min", "size_max")}

    summary = "a walled 6 x 6 m room of tables, chairs and 16 loose objects for the mobile robot to navigate (thesis 5.6.5)"

    def items(self) -> tuple[Item, ...]:
        return furnished_room_items(self.room)
