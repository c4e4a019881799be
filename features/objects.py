"""The chapter 8 object feature vector, and keeping track of objects between looks.

``object_features`` turns one detection into the 43 numbers of thesis 8.3.1.
``track`` matches a new look to the objects the robot already knows, so that an object
that vanished keeps its last seen position and shape with visibility 0 (its effect is
then a drop of visibility only, as DESIGN.md section 1 asks).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment

from afford.features.detect import Detection, RangeImage, RegionOfInterest, detect_objects
from afford.features.normals import grid_normals, normal_angles
from afford.features.schema import N_ANGLE_BINS, object_schema

__all__ = ["object_features", "normal_histograms", "match", "perceive", "track", "extents", "centres", "N_OBJECT_FEATURES"]

_SCHEMA = object_schema()
N_OBJECT_FEATURES = len(_SCHEMA)
_VISIBLE = _SCHEMA.visibility_index
_LO = np.array([_SCHEMA.index(f"{a}_min") for a in "xyz"])
_HI = np.array([_SCHEMA.index(f"{a}_max") for a in "xyz"])


def extents(f: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest corner (..., 3) of perceived objects' bounding boxes."""
    return f[..., _LO], f[..., _HI]


def centres(f: np.ndarray) -> np.ndarray:
    """Centres (..., 3) of perceived objects' bounding boxes."""
    lo, hi = extents(f)
    return (lo + hi) / 2

_ELEVATION_EDGES = np.linspace(-90.0, 90.0, N_ANGLE_BINS + 1)
_AZIMUTH_EDGES = np.linspace(-180.0, 180.0, N_ANGLE_BINS + 1)


def _histogram(values: np.ndarray, edges: np.ndarray) -> np.ndarray:
    counts, _ = np.histogram(values, bins=edges)
    total = counts.sum()
    return counts / total if total else counts.astype(float)


def normal_histograms(detection: Detection, camera: np.ndarray, normal_step: int = 5) -> np.ndarray:
    """The 36 shape features: normalised histograms of the surface normals' elevation and
    azimuth, 18 bins each (thesis 5.3.1 and 8.3.1)."""
    step = normal_step
    normals = grid_normals(detection.points, camera, n=step)
    while normals.shape[0] < 3 and step > 1:  # a small object: use nearer neighbours
        step -= 1
        normals = grid_normals(detection.points, camera, n=step)
    elevation, azimuth = normal_angles(normals)
    return np.concatenate([_histogram(elevation, _ELEVATION_EDGES), _histogram(azimuth, _AZIMUTH_EDGES)])


def object_features(detection: Detection, camera: np.ndarray, normal_step: int = 5) -> np.ndarray:
    """The 43-feature vector of one detected object (visibility 1)."""
    cloud = detection.cloud()
    lo = cloud.min(axis=0)
    hi = cloud.max(axis=0)
    position = np.column_stack([lo, hi]).ravel()  # x_min, x_max, y_min, y_max, z_min, z_max
    return np.concatenate([[1.0], position, normal_histograms(detection, camera, normal_step)])


def perceive(image: RangeImage, roi: RegionOfInterest, **detect_options) -> np.ndarray:
    """Detect every object in a range image; return their feature vectors (k, 43)."""
    detections = detect_objects(image, roi, **detect_options)
    if not detections:
        return np.empty((0, N_OBJECT_FEATURES))
    return np.stack([object_features(d, image.origin) for d in detections])


def track(known: np.ndarray, seen: np.ndarray, gate: float = 0.35) -> np.ndarray:
    """Match a new look to known objects by their centres.

    Parameters
    ----------
    known : (k, 43) array
        The objects as last perceived (visibility 0 rows are vanished ones).
    seen : (m, 43) array
        This look's detections.
    gate : float
        Centres further apart than this (metres) are not the same object.

    Returns
    -------
    (k, 43) array: each known object updated from its match; an unmatched one keeps its
    last features with visibility 0. Detections that match nothing are ignored (the
    robot tracks the objects it started with).
    """
    return match(known, seen, centres(known), centres(seen), gate, _VISIBLE)


def match(known: np.ndarray, seen: np.ndarray, known_at: np.ndarray, seen_at: np.ndarray,
          gate: float, visibility: int, pairs: bool = False):
    """Update ``known`` objects from the ``seen`` ones nearest where each was expected.

    ``known_at`` (k, p) are where the known objects are expected now and ``seen_at`` (m, p)
    where the detections are (any coordinates in which ``gate`` is a distance). Pairs are
    assigned one to one (Hungarian) within ``gate``; a known object left unmatched keeps its
    last features with its ``visibility`` column 0. With ``pairs``, also the matched
    (known, seen) index pairs.
    """
    out = known.copy()
    out[:, visibility] = 0.0
    matched: list[tuple[int, int]] = []
    if known.shape[0] and seen.shape[0]:
        cost = np.linalg.norm(np.asarray(known_at)[:, None, :] - np.asarray(seen_at)[None, :, :], axis=2)
        # An object already gone is matched only when no visible one can take the detection:
        # otherwise a dropped object landing near where another fell off would be mistaken for it.
        gone = known[:, visibility] < 0.5
        cost = cost + np.where(gone, gate, 0.0)[:, None]
        rows, cols = linear_sum_assignment(cost)
        for r, c in zip(rows, cols):
            if cost[r, c] - (gate if gone[r] else 0.0) <= gate:
                out[r] = seen[c]
                matched.append((int(r), int(c)))
    return (out, matched) if pairs else out
