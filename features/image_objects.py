"""Chapter 7's object features: objects as regions of the range image (thesis 7.3.1).

The mobile robot's 360 x 360 range image is compared with a scan of the empty world taken
from the same place on the robot (the *background*): a pixel that reads nearer than the
background by more than ``margin`` stands out, and what stands out is segmented into
objects as in chapter 8 (:func:`features.detect.detect_objects`: connected components whose
neighbouring ranges jump by less than 2 cm, boundary pixels dropped, median and Gaussian
smoothing). Each object is 44 numbers, named as the thesis names them:

``d_min``, ``d_avg``, ``d_max``
    the nearest, mean and farthest range of its pixels (metres, from the scanner);
``area``
    its pixels;
``r_t``, ``r_b``, ``c_l``, ``c_r``
    its bounding box in the image: top and bottom rows, counted up from the image's bottom
    row (so that a lifted object's bottom row is high, as in the thesis's goal
    ``r_b > 180``: row 180 of 360 is the scanner's horizontal), and left and right columns
    (column 0 looks left);
``phi_01`` .. ``phi_18``, ``theta_01`` .. ``theta_18``
    normalised histograms of its surface normals' latitude (elevation) and longitude
    (azimuth), 18 bins each (thesis 5.3.1).

Beside these 44 the vector carries the tracker's ``visibility`` (1 seen, 0 gone, as in
chapter 8), so that an object a move takes out of view stays in the state with its last
features and the planner knows it is gone: 45 columns in all.
"""

from __future__ import annotations

import numpy as np

from afford.features.detect import Detection, RangeImage, detect_objects
from afford.features.objects import match, normal_histograms
from afford.features.schema import N_ANGLE_BINS, Channel, FeatureSchema

__all__ = ["image_object_schema", "image_object_features", "perceive_against", "track_expected", "stand_out"]


def image_object_schema() -> FeatureSchema:
    """The 44 features of thesis 7.3.1, after the tracker's visibility."""
    names = ["visibility", "d_min", "d_avg", "d_max", "area", "r_t", "r_b", "c_l", "c_r"]
    channels = ["visibility", "distance", "distance", "distance", "area", "image", "image", "image", "image"]
    for angle in ("phi", "theta"):
        names += [f"{angle}_{i + 1:02d}" for i in range(N_ANGLE_BINS)]
        channels += ["shape"] * N_ANGLE_BINS
    first = len(names) - 2 * N_ANGLE_BINS
    return FeatureSchema(
        tuple(names), tuple(channels), visibility="visibility",
        histograms=((first, first + N_ANGLE_BINS), (first + N_ANGLE_BINS, first + 2 * N_ANGLE_BINS)),
        channel_info=(Channel("visibility", "", 0.5, 1.0), Channel("distance", "m", 0.05, 0.1),
                      Channel("area", "px", 200.0, 500.0), Channel("image", "px", 10.0, 20.0),
                      Channel("shape", "fraction", 0.1, 0.5)),
    )


_SCHEMA = image_object_schema()
_VISIBLE = _SCHEMA.visibility_index


def stand_out(image: RangeImage, background: np.ndarray, margin: float = 0.03) -> np.ndarray:
    """Pixels nearer than the empty world's scan by more than ``margin`` (and not the robot's own)."""
    r = image.ranges
    out = np.isfinite(r) & (r < background - margin)
    if image.own_body is not None:
        out &= ~image.own_body
    return out


def image_object_features(detection: Detection, image: RangeImage) -> np.ndarray:
    """The 45-column vector (visibility 1, then the thesis's 44) of one detected object."""
    mask = detection.mask
    rr, cc = np.nonzero(mask)
    r0, c0 = detection.origin
    height = image.shape[0]
    d = np.linalg.norm(detection.cloud() - image.origin, axis=1)
    box = [height - 1 - (r0 + rr.min()), height - 1 - (r0 + rr.max()), c0 + cc.min(), c0 + cc.max()]
    head = [1.0, d.min(), d.mean(), d.max(), float(mask.sum()), *box]
    return np.concatenate([np.asarray(head, dtype=float), normal_histograms(detection, image.origin)])


def perceive_against(image: RangeImage, background: np.ndarray, margin: float = 0.03,
                     **detect_options) -> np.ndarray:
    """Every object that stands out of the background: (k, 45) feature vectors."""
    detections = detect_objects(image, candidate=stand_out(image, background, margin), **detect_options)
    if not detections:
        return np.empty((0, len(_SCHEMA)))
    return np.stack([image_object_features(det, image) for det in detections])


def track_expected(known: np.ndarray, seen: np.ndarray, expected: np.ndarray, seen_at: np.ndarray,
                   gate: float = 0.30, wide: float = 1.0) -> np.ndarray:
    """Match a new look to the known objects by where each was expected to be.

    After a move every object shifts in the robot's frame by the robot's own motion, so
    ``expected`` (k, 3) holds each known object's last place moved by the odometry's
    inverse, and ``seen_at`` (m, 3) the detections' places. Pairs within ``gate`` metres
    match first, one to one; then what is left of both is matched within ``wide`` metres
    (an object the robot pushed or that rolled away is not where the robot's own motion
    puts it). A known object left unmatched keeps its features with visibility 0.
    """
    out, pairs = match(known, seen, expected, seen_at, gate, _VISIBLE, pairs=True)
    lost = np.flatnonzero((out[:, _VISIBLE] < 0.5) & (known[:, _VISIBLE] >= 0.5))
    free = np.setdiff1d(np.arange(seen.shape[0]), [c for _, c in pairs])
    if lost.size and free.size:
        out[lost] = match(known[lost], seen[free], np.asarray(expected)[lost], np.asarray(seen_at)[free], wide, _VISIBLE)
    return out
