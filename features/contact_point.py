"""Contact-point features: the object as the hand will meet it (thesis 9.3.1.2).

Chapter 9's behaviours act on an object's closest point (CP) to the robot, so its 25
features describe the CP and its neighbourhood rather than the whole object:

- ``cp``: the CP's position (x, y, z in the robot frame), 3 features;
- ``border``: the distance from the CP to the object's border, scanning the range image
  up, down, left and right from the CP's pixel, 4;
- ``patch``: the distance from the CP to the centre of a 5 x 5 surface patch next to it in
  each of those directions, 4;
- ``normal``: each patch's mean surface normal (x, y, z), 12;
- ``visibility``: the object is seen (1) or gone (0), 1;
- ``touch``: the hand touches the object (the robot's own tactile reading), 1.

The CP is the object's pixel nearest the robot's shoulder in the horizontal plane. As in
the thesis the camera stands across the table, so the face the hand meets is mostly out of
its view; the CP is then on the visible surface's edge nearest the robot, which for the
symmetric objects of the thesis says the same about the hidden face. Surface normals come
from Open3D (``estimate_normals`` over the object's points, turned to face the camera).
A patch that holds no object pixel (the CP sits on the border) has distance 0 and normal 0.
"""

from __future__ import annotations

import numpy as np
import open3d as o3d

from afford.features.detect import Detection, RangeImage, RegionOfInterest, detect_objects
from afford.features.schema import Channel, FeatureSchema

__all__ = ["contact_point_schema", "contact_point_features", "perceive_contact_points", "DIRECTIONS",
           "N_CONTACT_FEATURES", "cp_positions"]

#: Scan directions in the image, as (row step, column step).
DIRECTIONS = {"up": (-1, 0), "down": (1, 0), "left": (0, -1), "right": (0, 1)}
#: Half the side of a surface patch (5 x 5 pixels), and how far its centre lies from the CP.
_PATCH_HALF, _PATCH_OFFSET = 2, 3


def contact_point_schema() -> FeatureSchema:
    """The 25 contact-point features in six channels (see the module docstring)."""
    names: list[str] = ["visibility", "cp_x", "cp_y", "cp_z"]
    channels: list[str] = ["visibility", "cp", "cp", "cp"]
    names += [f"border_{d}" for d in DIRECTIONS]
    channels += ["border"] * 4
    names += [f"patch_{d}" for d in DIRECTIONS]
    channels += ["patch"] * 4
    for d in DIRECTIONS:
        names += [f"normal_{d}_{a}" for a in "xyz"]
        channels += ["normal"] * 3
    names.append("touch")
    channels.append("touch")
    return FeatureSchema(
        tuple(names), tuple(channels), visibility="visibility",
        channel_info=(Channel("visibility", "", 0.5, 1.0), Channel("cp", "m", 0.05, 0.1),
                      Channel("border", "m", 0.05, 0.1), Channel("patch", "m", 0.02, 0.1),
                      Channel("normal", "", 0.3, 0.5), Channel("touch", "", 0.5, 1.0)),
        roles=(("height", "cp_z"),),
    )


_SCHEMA = contact_point_schema()
N_CONTACT_FEATURES = len(_SCHEMA)
_CP = np.array([_SCHEMA.index(f"cp_{a}") for a in "xyz"])
_TOUCH = _SCHEMA.index("touch")


def cp_positions(f: np.ndarray) -> np.ndarray:
    """The contact points (..., 3) of perceived objects."""
    return np.asarray(f)[..., _CP]


def _normals(detection: Detection, camera: np.ndarray) -> np.ndarray:
    """(h, w, 3) unit normals of the detection's pixels (0 outside its mask), facing the camera."""
    cloud = detection.cloud()
    out = np.zeros(detection.points.shape)
    if cloud.shape[0] < 3:
        return out
    pcd = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(cloud))
    pcd.estimate_normals(o3d.geometry.KDTreeSearchParamKNN(knn=min(12, cloud.shape[0])))
    n = np.asarray(pcd.normals)
    flip = np.einsum("ij,ij->i", n, camera - cloud) < 0
    n[flip] *= -1.0
    out[detection.mask] = n
    return out


def contact_point_features(detection: Detection, camera: np.ndarray, shoulder=(0.0, 0.0),
                           touch: float = 0.0) -> np.ndarray:
    """The 25 features of one detected object (visibility 1)."""
    mask, points = detection.mask, detection.points
    rr, cc = np.nonzero(mask)
    xy = points[rr, cc, :2] - np.asarray(shoulder, dtype=float)
    k = int(np.argmin(np.einsum("ij,ij->i", xy, xy)))
    r0, c0 = int(rr[k]), int(cc[k])
    cp = points[r0, c0]
    normals = _normals(detection, camera)
    h, w = mask.shape
    borders, patches, patch_normals = [], [], []
    for dr, dc in DIRECTIONS.values():
        r, c = r0, c0
        while 0 <= r + dr < h and 0 <= c + dc < w and mask[r + dr, c + dc]:
            r, c = r + dr, c + dc
        borders.append(float(np.linalg.norm(points[r, c] - cp)))
        pr, pc = r0 + dr * _PATCH_OFFSET, c0 + dc * _PATCH_OFFSET
        rs = slice(max(pr - _PATCH_HALF, 0), max(pr + _PATCH_HALF + 1, 0))
        cs = slice(max(pc - _PATCH_HALF, 0), max(pc + _PATCH_HALF + 1, 0))
        inside = mask[rs, cs]
        if inside.any():
            patches.append(float(np.linalg.norm(points[rs, cs][inside].mean(axis=0) - cp)))
            mean = normals[rs, cs][inside].mean(axis=0)
            norm = float(np.linalg.norm(mean))
            patch_normals.append(mean / norm if norm > 1e-9 else np.zeros(3))
        else:
            patches.append(0.0)
            patch_normals.append(np.zeros(3))
    return np.concatenate([[1.0], cp, borders, patches, np.concatenate(patch_normals), [float(touch)]])


def perceive_contact_points(image: RangeImage, roi: RegionOfInterest, shoulder=(0.0, 0.0),
                            **detect_options) -> tuple[np.ndarray, list[Detection]]:
    """Detect every object in a range image; their contact-point features (k, 25) with touch 0
    (the world fills in its tactile reading per object), and the detections."""
    detections = detect_objects(image, roi, **detect_options)
    if not detections:
        return np.empty((0, N_CONTACT_FEATURES)), []
    return np.stack([contact_point_features(d, image.origin, shoulder) for d in detections]), detections
