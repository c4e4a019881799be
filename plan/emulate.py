"""Emulation (thesis 8.6-8.7): turn a shown scene into a goal, by channel priority.

The robot perceives the goal scene and keeps what matters most: first visibility (an
empty table means: make the objects vanish), then position (an object shown somewhere:
bring an object there), then shape. With two objects shown, what it keeps is their
relative position (the difference of their position features), so any two objects can be
brought into the same relation.
"""

from __future__ import annotations

import numpy as np

from features import FeatureSchema
from plan.goals import DEFAULT_TOLERANCE, Constraint, Goal

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
    seen = observed[observed[:, 0] >= 0.5] if observed.size else observed.reshape(0, len(schema))
    k = start.shape[0]
    vis = schema.index("visibility")
    if seen.shape[0] == 0:  # visibility first: nothing shown, so nothing should be seen
        return Goal(tuple(Constraint(i, vis, "visibility", 0.0, DEFAULT_TOLERANCE["visibility"], "visibility")
                          for i in range(k)))
    if seen.shape[0] == 1:  # one object shown: an object should be where it is
        # Its footprint on the table plane, loosely (pushes move objects in steps of a
        # decimetre or more, and the start object need not have the shown one's size), and
        # the height of its bottom (lifted or not); its top depends on the object's size.
        f = seen[0]
        out = [Constraint("*", schema.index(n), n, float(f[schema.index(n)]), 2 * tolerance, "position")
               for n in ("x_min", "x_max", "y_min", "y_max")]
        z = schema.index("z_min")
        out.append(Constraint("*", z, "z_min", float(f[z]), 1.5 * tolerance, "position"))
        return Goal(tuple(out))
    if k < 2:
        raise ValueError("the shown scene relates two objects, but the start scene has fewer than two")
    # Two (or more) shown: keep the relation of the first two, on the table plane.
    a, b = seen[0], seen[1]
    out = []
    for n in ("x_min", "x_max", "y_min", "y_max"):
        j = schema.index(n)
        out.append(Constraint((0, 1), j, n, float(a[j] - b[j]), 2 * tolerance, "position"))
    return Goal(tuple(out))
