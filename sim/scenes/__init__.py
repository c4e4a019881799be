"""The scene library: importing this package registers every scene in it."""

from afford.sim.scenes import crane_lift, grasp, room, table, traverse, traverse_body, traverse_furniture, traverse_gaps, traverse_one, traverse_ramps, traverse_room  # noqa: F401
