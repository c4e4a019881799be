"""Surface normals of an object's points, from its neighbours in the range grid.

Thesis 8.3.1: N(r, c) = (p(r-n, c) - p(r, c)) x (p(r, c-n) - p(r, c)) with n = 5. Using
neighbours five pixels away, not adjacent ones, averages out most of the range noise;
a pixel whose neighbour lies outside the object (NaN) gets no normal. Normals are turned
to face the camera, since a range camera only sees surfaces that face it.
"""

from __future__ import annotations

import numpy as np

__all__ = ["grid_normals", "normal_angles"]


def grid_normals(points: np.ndarray, camera: np.ndarray, n: int = 5) -> np.ndarray:
    """Unit normals (k, 3) of the grid points that have both neighbours.

    Parameters
    ----------
    points : (H, W, 3) array
        Points in the robot frame, NaN where there is no object point.
    camera : (3,) array
        Camera centre, to orient normals towards it.
    n : int
        Neighbour distance in pixels.
    """
    h, w, _ = points.shape
    if h <= n or w <= n:
        return np.empty((0, 3))
    p = points[n:, n:]
    up = points[:-n, n:]      # p(r - n, c)
    left = points[n:, :-n]    # p(r, c - n)
    normal = np.cross(up - p, left - p)
    normal = normal.reshape(-1, 3)
    centre = p.reshape(-1, 3)
    ok = np.all(np.isfinite(normal), axis=1)
    normal, centre = normal[ok], centre[ok]
    length = np.linalg.norm(normal, axis=1)
    good = length > 1e-12
    normal = normal[good] / length[good, None]
    towards = camera - centre[good]
    flip = np.einsum("ij,ij->i", normal, towards) < 0
    normal[flip] *= -1.0
    return normal


def normal_angles(normals: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Elevation (latitude, -90..90) and azimuth (longitude, -180..180) in degrees.

    Elevation is the angle between the normal and the horizontal plane (90 for a table-like
    top); azimuth is the heading of its horizontal part, from the frontal axis towards the
    left. The thesis measures from the x-z plane of its camera; in the robot frame this
    pair separates tops, sides and curved surfaces the same way.
    """
    elevation = np.degrees(np.arcsin(np.clip(normals[:, 2], -1.0, 1.0)))
    azimuth = np.degrees(np.arctan2(normals[:, 1], normals[:, 0]))
    return elevation, azimuth
