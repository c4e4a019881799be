"""The chapter-5 3D range scanner (thesis 5.3.1), ray-cast with Open3D.

KURT3D's scanner is a 2D laser range finder whose scan plane is pitched up and down: within
a plane it sweeps 180 deg (angle alpha, 0 = left, 90 = straight ahead, 180 = right) and the
plane is pitched by beta (+82.8 deg up to -82.8 deg down). A ray's direction in the robot
frame (x forward, y left, z up) is the thesis's formula with the scanner's axes named as
the robot's::

    d(alpha, beta) = (sin(alpha) cos(beta), cos(alpha), sin(alpha) sin(beta))

720 x 720 rays: columns sweep alpha over 180 deg (0.25 deg apart, as a SICK scanner does),
rows sweep beta from +82.8 deg (top row) to -82.8 deg (bottom row, 0.23 deg apart). Each
ray returns the distance to the first surface it meets plus Gaussian noise; beyond
``max_range`` (and where nothing is hit) the range is ``inf``. The image is then
down-scaled to 360 x 360 by taking the nearest range of every 2 x 2 block, as the thesis
did "in order to reduce the noise"; the down-scaled pixel's direction is the mean of its
block's, renormalised. Pixels whose block saw the robot's own body are marked in
``RangeImage.own_body``.

Rays are unit vectors, so Open3D's ``t_hit`` is the range along the ray.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from afford.features import RangeImage
from afford.features.errors import DataError
from afford.sim.camera import MeshInstance

__all__ = ["ScannerConfig", "RangeScanner", "scan_directions"]


@dataclass(frozen=True)
class ScannerConfig:
    """The scanner's ray grid and noise (degrees, metres)."""

    rows: int = 720
    cols: int = 720
    sweep_deg: float = 180.0
    """Angle swept within the scan plane (alpha)."""
    pitch_deg: float = 82.8
    """The scan plane is pitched from +pitch_deg (up) to -pitch_deg (down)."""
    downscale: int = 2
    """Block size of the min-downscale (720 -> 360); 1 keeps the raw image."""
    noise: float = 0.003
    """Standard deviation of the Gaussian range noise, metres."""
    max_range: float = 4.0
    """Farther hits read as misses (``inf``), so the far floor does not dominate."""

    def __post_init__(self) -> None:
        if self.downscale < 1 or self.rows % self.downscale or self.cols % self.downscale:
            raise DataError(f"the scanner's {self.rows} x {self.cols} rays do not split into "
                             f"{self.downscale} x {self.downscale} blocks")


def scan_directions(config: ScannerConfig) -> np.ndarray:
    """Unit ray directions (rows, cols, 3) in the scanner's frame (= the robot's axes)."""
    c = config
    alpha = np.radians((np.arange(c.cols) + 0.5) * c.sweep_deg / c.cols + (90.0 - c.sweep_deg / 2))
    beta = np.radians(c.pitch_deg - (np.arange(c.rows) + 0.5) * 2 * c.pitch_deg / c.rows)
    a, b = alpha[None, :], beta[:, None]
    d = np.stack(np.broadcast_arrays(np.sin(a) * np.cos(b), np.cos(a), np.sin(a) * np.sin(b)), axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def _block_min(a: np.ndarray, k: int) -> np.ndarray:
    """Minimum of every k x k block (strided views: a fraction of a millisecond)."""
    out = a[0::k, 0::k].copy()
    for i in range(k):
        for j in range(k):
            if i or j:
                np.minimum(out, a[i::k, j::k], out=out)
    return out


class RangeScanner:
    """Casts the scanner's rays from ``origin`` (robot frame) against posed meshes.

    ``scan`` takes the meshes in the world frame and the 4 x 4 transform from the world
    into the robot's frame (default: the robot stands at the world's origin); the image
    comes back in the robot frame.
    """

    def __init__(self, config: ScannerConfig = ScannerConfig(), origin=(0.0, 0.0, 0.45), threads: int = 1):
        self.config = c = config
        self.origin = np.asarray(origin, dtype=float)
        self.threads = threads
        self.raw_directions = scan_directions(c)
        k = c.downscale
        d = self.raw_directions.reshape(c.rows // k, k, c.cols // k, k, 3).mean(axis=(1, 3))
        self.directions = d / np.linalg.norm(d, axis=-1, keepdims=True)
        self._rays = np.empty((c.rows * c.cols, 6), dtype=np.float32)
        self._rays[:, :3] = self.origin
        self._rays[:, 3:] = self.raw_directions.reshape(-1, 3)

    def cast(self, meshes: list[MeshInstance],
             world_to_robot: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Noise-free ranges (rows, cols) of the full ray grid, and which rays met the robot's own body."""
        c = self.config
        scene = o3d.t.geometry.RaycastingScene()
        own_ids = []
        for m in meshes:
            v = m.world_vertices()
            if world_to_robot is not None:
                v = v @ world_to_robot[:3, :3].T + world_to_robot[:3, 3]
            gid = scene.add_triangles(o3d.core.Tensor(v.astype(np.float32)),
                                      o3d.core.Tensor(m.triangles.astype(np.uint32)))
            if m.own_body:
                own_ids.append(gid)
        hits = scene.cast_rays(o3d.core.Tensor(self._rays), nthreads=self.threads)
        t = hits["t_hit"].numpy().reshape(c.rows, c.cols)
        own = np.isin(hits["geometry_ids"].numpy(), own_ids).reshape(c.rows, c.cols)
        return t, own

    def scan(self, meshes: list[MeshInstance], rng: np.random.Generator,
             world_to_robot: np.ndarray | None = None) -> RangeImage:
        """One noisy, down-scaled range image in the robot frame."""
        c = self.config
        t, own = self.cast(meshes, world_to_robot)
        t = t + c.noise * rng.standard_normal(t.shape, dtype=np.float32)  # inf stays inf
        t[t > c.max_range] = np.inf
        k = c.downscale
        if k > 1:
            t = _block_min(t, k)
            own = own.reshape(c.rows // k, k, c.cols // k, k).any(axis=(1, 3))
        return RangeImage(ranges=t, directions=self.directions, origin=self.origin.copy(), own_body=own)
