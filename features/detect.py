"""Object detection in a range image (thesis Algorithm 4).

The robot keeps the pixels that lie in the region of interest (the volume over the table)
and are not its own body, splits them into objects by connected-component labelling where
neighbouring ranges jump by less than ``jump`` (2 cm in the thesis), drops each object's
boundary pixels, and smooths what remains with 5 x 5 median and Gaussian filters.

The thesis also filtered by confidence and amplitude (a SwissRanger's dark-surface noise);
a simulated camera has no such pixels, so those tests reduce to "the ray hit something".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from scipy import ndimage
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = ["RangeImage", "RegionOfInterest", "Detection", "detect_objects"]


@dataclass(frozen=True)
class RangeImage:
    """What a range camera gives: one range per ray on a grid.

    Parameters
    ----------
    ranges : (H, W) array
        Distance along each ray in metres; ``inf`` where the ray hit nothing.
    directions : (H, W, 3) array
        Unit ray directions in the robot frame.
    origin : (3,) array
        The camera centre in the robot frame.
    own_body : (H, W) bool array, optional
        Pixels that see the robot's own hand (a robot knows its body and filters it out).
    """

    ranges: np.ndarray
    directions: np.ndarray
    origin: np.ndarray
    own_body: np.ndarray | None = None

    @property
    def shape(self) -> tuple[int, int]:
        return self.ranges.shape  # type: ignore[return-value]

    def points(self, ranges: np.ndarray | None = None) -> np.ndarray:
        """3-D points (H, W, 3) of ``ranges`` (default: the raw ranges)."""
        r = self.ranges if ranges is None else ranges
        return self.origin + r[..., None] * self.directions


@dataclass(frozen=True)
class RegionOfInterest:
    """An axis-aligned box in the robot frame; points outside it are not objects."""

    x: tuple[float, float]
    y: tuple[float, float]
    z: tuple[float, float]

    def contains(self, p: np.ndarray) -> np.ndarray:
        with np.errstate(invalid="ignore"):
            return (
                (p[..., 0] >= self.x[0]) & (p[..., 0] <= self.x[1])
                & (p[..., 1] >= self.y[0]) & (p[..., 1] <= self.y[1])
                & (p[..., 2] >= self.z[0]) & (p[..., 2] <= self.z[1])
            )


@dataclass(frozen=True)
class Detection:
    """One detected object: its interior pixels and their smoothed 3-D points."""

    mask: np.ndarray          # (h, w) bool, interior pixels after boundary removal, in a crop
    points: np.ndarray        # (h, w, 3) smoothed points of the crop, NaN outside the mask
    origin: tuple[int, int]   # the crop's top-left pixel in the full image

    @property
    def n_pixels(self) -> int:
        return int(self.mask.sum())

    def cloud(self) -> np.ndarray:
        """The object's points as an (n, 3) array."""
        return self.points[self.mask]


def _components(candidate: np.ndarray, ranges: np.ndarray, jump: float) -> np.ndarray:
    """Label image of 4-connected components whose neighbouring ranges differ < jump."""
    h, w = candidate.shape
    flat = np.flatnonzero(candidate)
    node = np.full(h * w, -1, dtype=np.int64)
    node[flat] = np.arange(flat.size)
    r = ranges.ravel()
    rows, cols = [], []
    for step, valid in ((1, (flat % w) < w - 1), (w, flat < (h - 1) * w)):
        a = flat[valid]
        b = a + step
        ok = candidate.ravel()[b]
        a, b = a[ok], b[ok]
        ok = np.abs(r[a] - r[b]) < jump
        rows.append(node[a[ok]])
        cols.append(node[b[ok]])
    i = np.concatenate(rows)
    j = np.concatenate(cols)
    graph = coo_matrix((np.ones(i.size, dtype=np.int8), (i, j)), shape=(flat.size, flat.size))
    _, comp = connected_components(graph, directed=False)
    labels = np.zeros(h * w, dtype=np.int64)
    labels[flat] = comp + 1
    return labels.reshape(h, w)


def _masked_median(values: np.ndarray, mask: np.ndarray, size: int) -> np.ndarray:
    """Median of the in-mask values of each in-mask pixel's window (NaN-free, vectorised)."""
    pad = size // 2
    v = np.pad(np.where(mask, values, np.nan), pad, constant_values=np.nan)
    windows = np.sort(sliding_window_view(v, (size, size))[mask].reshape(-1, size * size), axis=1)
    k = np.count_nonzero(np.isfinite(windows), axis=1)  # NaNs sort last
    rows = np.arange(windows.shape[0])
    return (windows[rows, (k - 1) // 2] + windows[rows, k // 2]) / 2


def _masked_gaussian(values: np.ndarray, mask: np.ndarray, sigma: float, size: int) -> np.ndarray:
    truncate = (size // 2) / sigma
    m = mask.astype(float)
    num = ndimage.gaussian_filter(np.where(mask, values, 0.0), sigma, truncate=truncate, mode="constant")
    den = ndimage.gaussian_filter(m, sigma, truncate=truncate, mode="constant")
    return num[mask] / den[mask]


def detect_objects(
    image: RangeImage,
    roi: RegionOfInterest | None = None,
    *,
    candidate: np.ndarray | None = None,
    jump: float = 0.02,
    min_pixels: int = 12,
    window: int = 5,
) -> list[Detection]:
    """Find the objects in a range image, as thesis Algorithm 4.

    Parameters
    ----------
    image : RangeImage
    roi : RegionOfInterest, optional
        The volume over the table; the table top itself must lie below it.
    candidate : (H, W) bool array, optional
        Pixels that may belong to objects, found otherwise (chapter 7: the pixels that
        stand out of a scan of the empty world). With ``roi`` too, both must hold.
    jump : float
        Neighbouring pixels whose ranges differ by this much (metres) belong to
        different objects.
    min_pixels : int
        Objects with fewer interior pixels are dropped as noise.
    window : int
        Size of the median and Gaussian filter windows.

    Returns
    -------
    list of Detection, ordered by their first pixel in raster order.
    """
    ranges = image.ranges
    given = candidate
    candidate = np.isfinite(ranges)
    if given is not None:
        candidate &= np.asarray(given, dtype=bool)
    if roi is not None:
        hit = np.flatnonzero(candidate)
        points = image.origin + ranges.ravel()[hit, None] * image.directions.reshape(-1, 3)[hit]
        candidate.ravel()[hit] = roi.contains(points)
    if image.own_body is not None:
        candidate &= ~image.own_body
    if not candidate.any():
        return []
    labels = _components(candidate, ranges, jump)

    # Boundary pixels: a 4-neighbour carries another label (or none).
    padded = np.pad(labels, 1, constant_values=0)
    interior = labels > 0
    for dr, dc in ((0, 1), (2, 1), (1, 0), (1, 2)):
        interior &= padded[dr : dr + labels.shape[0], dc : dc + labels.shape[1]] == labels

    detections = []
    ids, counts = np.unique(labels[interior], return_counts=True)
    for label, count in zip(ids, counts):
        if count < min_pixels:
            continue
        mask = interior & (labels == label)
        rr, cc = np.nonzero(mask)
        r0, r1 = max(rr.min() - window, 0), rr.max() + window + 1
        c0, c1 = max(cc.min() - window, 0), cc.max() + window + 1
        sub_mask = mask[r0:r1, c0:c1]
        sub = ranges[r0:r1, c0:c1]
        smooth = sub.copy()
        smooth[sub_mask] = _masked_median(sub, sub_mask, window)
        smooth[sub_mask] = _masked_gaussian(smooth, sub_mask, sigma=1.0, size=window)
        smooth[~sub_mask] = np.nan
        points = image.origin + smooth[..., None] * image.directions[r0:r1, c0:c1]
        detections.append(Detection(mask=sub_mask, points=points, origin=(int(r0), int(c0))))
    return detections
