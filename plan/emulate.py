"""Emulation (thesis 8.6-8.7): turn a shown scene into a goal, by channel priority.

The robot perceives the goal scene and keeps what matters most: first visibility (an
empty table means: make the objects vanish), then position (an object shown somewhere:
bring an object there), then shape. With two objects shown, what it keeps is their
relative position (the difference of their position features), so any two objects can be
brought into the same relation.
"""

from __future__ import annotations

import numpy as np

from afford.features import FeatureSchema
from afford.features.errors import DataError
from afford.plan.goals import Constraint, Goal

__all__ = ["goal_from_observation"]



def goal_from_observation(observed: np.ndarray, start: np.ndarray, schema: FeatureSchema,
                          tolerance: float = 0.06) -> Goal:
    """Constraints that make the start scene look like the observed one.

    Parameters
    ----------
    observed : (m, d) array
        The goal scene as perceived (visible objects only count).
    start : (k, d) array
        The start scene as perceived.
    """
    needed = ("x_min", "x_max", "y_min", "y_max", "z_min")
    if schema.visibility_index is None or any(n not in schema.names for n in needed):
        raise DataError("emulation is chapter 8's: it needs entities that can vanish and have x, y and z extents, "
                         "which this model's features do not have")
    seen = observed[schema.visible(observed)] if observed.size else observed.reshape(0, len(schema))
    k = start.shape[0]
    vis = schema.visibility_index
    vis_ch = schema.channel(schema.channels[vis])
    pos = schema.channel(schema.channels[schema.index("x_min")])

    def c(obj, n, value, tol):
        j = schema.index(n)
        return Constraint(obj, j, n, value, tol, schema.channels[j], pos.scale)

    if seen.shape[0] == 0:  # visibility first: nothing shown, so nothing should be seen
        return Goal(tuple(Constraint(i, vis, schema.visibility, 0.0, vis_ch.tolerance, schema.channels[vis], vis_ch.scale)
                          for i in range(k)))
    if seen.shape[0] == 1:  # one object shown: an object should be where it is
        # Its footprint on the table plane, loosely (pushes move objects in steps of a
        # decimetre or more, and the start object need not have the shown one's size), and
        # the height of its bottom (lifted or not); its top depends on the object's size.
        f = seen[0]
        out = [c("*", n, float(f[schema.index(n)]), 2 * tolerance) for n in ("x_min", "x_max", "y_min", "y_max")]
        out.append(c("*", "z_min", float(f[schema.index("z_min")]), 1.5 * tolerance))
        return Goal(tuple(out))
    if k < 2:
        raise DataError("the shown scene relates two objects, but the start scene has fewer than two")
    # Two (or more) shown: keep the relation of the first two, on the table plane.
    a, b = seen[0], seen[1]
    out = []
    for n in ("x_min", "x_max", "y_min", "y_max"):
        j = schema.index(n)
        out.append(c((0, 1), n, float(a[j] - b[j]), 2 * tolerance))
    return Goal(tuple(out))
