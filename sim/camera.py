"""The simulated range camera (thesis section 4.2), ray-cast with Open3D.

A grid of ``width`` x ``height`` rays leaves the camera centre ``step_deg`` apart in both
directions; each returns the distance to the first surface it meets, plus Gaussian noise.
Rays are built here with unit length, so Open3D's ``t_hit`` is the range along the ray
(its own pinhole rays are not unit length: their ``t_hit`` is depth). Misses are ``inf``.

Speed: the static background (the table) is cast once per camera; each capture casts only
the rays whose line passes through the bounding box of a moving body (an object or a
part of the hand) and keeps the nearer hit. The image is the same as casting everything every time.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from afford.features import RangeImage

__all__ = ["CameraConfig", "RangeCamera", "MeshInstance"]


@dataclass(frozen=True)
class CameraConfig:
    width: int = 176
    height: int = 144
    step_deg: float = 0.23
    position: tuple[float, float, float] = (0.75, -1.30, 1.80)
    look_at: tuple[float, float, float] = (0.75, 0.0, 0.80)
    noise: float = 0.003  # metres, standard deviation of the range noise


@dataclass(frozen=True)
class MeshInstance:
    """A mesh in its body frame, a pose (position, quaternion wxyz) and whether it is the robot."""

    vertices: np.ndarray
    triangles: np.ndarray
    position: np.ndarray
    quaternion: np.ndarray
    own_body: bool = False

    def world_vertices(self) -> np.ndarray:
        return self.vertices @ _rotation(self.quaternion).T + self.position


def _rotation(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q / np.linalg.norm(q)
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
        [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
        [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
    ])


class RangeCamera:
    """Casts the ray grid against posed meshes and returns a :class:`RangeImage`."""

    def __init__(self, config: CameraConfig = CameraConfig(), threads: int = 1):
        self.config = c = config
        self.threads = threads
        origin = np.asarray(c.position, dtype=float)
        forward = np.asarray(c.look_at, dtype=float) - origin
        forward /= np.linalg.norm(forward)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        down = np.cross(forward, right)
        step = np.radians(c.step_deg)
        cols = np.tan((np.arange(c.width) - (c.width - 1) / 2) * step)
        rows = np.tan((np.arange(c.height) - (c.height - 1) / 2) * step)
        d = forward + cols[None, :, None] * right + rows[:, None, None] * down
        self.directions = d / np.linalg.norm(d, axis=2, keepdims=True)
        self._forward, self._right, self._down = forward, right, down
        self.origin = origin
        self._flat = self.directions.reshape(-1, 3)
        self._static_key: object = None
        self._static_ranges = np.full(self._flat.shape[0], np.inf)

    def set_static(self, meshes: list[MeshInstance], key: object) -> None:
        """Cast the full grid once against what never moves (the table), and remember it.

        Later captures cast only the rays that can meet a moving body and take the nearer
        of the two hits, which is the same image for a fraction of the work.
        """
        if key == self._static_key:
            return
        hits = self._cast(meshes, np.arange(self._flat.shape[0]))[0]
        self._static_ranges = hits
        self._static_key = key

    def _rays_through(self, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
        """Indices of the rays that may meet the axis-aligned box [lo, hi].

        The box's eight corners are projected into the grid; every ray inside the pixel
        rectangle they span (plus one pixel) is cast. The grid is uniform in angle, so the
        rectangle in tangent space bounds the box's image exactly as in a pinhole camera.
        """
        c = self.config
        corners = np.array(np.meshgrid(*zip(lo, hi), indexing="ij")).reshape(3, -1).T - self.origin
        depth = corners @ self._forward
        if np.any(depth <= 1e-6):  # part of the box is behind the camera: cast everything
            return np.arange(self._flat.shape[0])
        step = np.radians(c.step_deg)
        col = np.arctan((corners @ self._right) / depth) / step + (c.width - 1) / 2
        row = np.arctan((corners @ self._down) / depth) / step + (c.height - 1) / 2
        c0, c1 = max(int(np.floor(col.min())) - 1, 0), min(int(np.ceil(col.max())) + 1, c.width - 1)
        r0, r1 = max(int(np.floor(row.min())) - 1, 0), min(int(np.ceil(row.max())) + 1, c.height - 1)
        if c0 > c1 or r0 > r1:
            return np.empty(0, dtype=np.int64)
        rr, cc = np.mgrid[r0 : r1 + 1, c0 : c1 + 1]
        return (rr * c.width + cc).ravel()

    def _cast(self, meshes: list[MeshInstance], rays: np.ndarray) -> tuple[np.ndarray, np.ndarray, list[int]]:
        scene = o3d.t.geometry.RaycastingScene()
        own_ids = []
        for m in meshes:
            gid = scene.add_triangles(o3d.core.Tensor(m.world_vertices().astype(np.float32)),
                                      o3d.core.Tensor(m.triangles.astype(np.uint32)))
            if m.own_body:
                own_ids.append(gid)
        origin = np.broadcast_to(self.origin, (rays.size, 3))
        tensor = o3d.core.Tensor(np.concatenate([origin, self._flat[rays]], axis=1).astype(np.float32))
        hits = scene.cast_rays(tensor, nthreads=self.threads)
        return hits["t_hit"].numpy().astype(np.float64), hits["geometry_ids"].numpy(), own_ids

    def capture(self, meshes: list[MeshInstance], rng: np.random.Generator) -> RangeImage:
        """A noisy range image of the static background plus ``meshes`` (the moving bodies)."""
        shape = (self.config.height, self.config.width)
        ranges = self._static_ranges.copy()
        own = np.zeros(ranges.size, dtype=bool)
        if meshes:
            wanted = np.zeros(ranges.size, dtype=bool)
            for m in meshes:
                b = m.world_vertices()
                wanted[self._rays_through(b.min(axis=0) - 0.005, b.max(axis=0) + 0.005)] = True
            rays = np.flatnonzero(wanted)
            if rays.size:
                t, ids, own_ids = self._cast(meshes, rays)
                nearer = t < ranges[rays]
                ranges[rays[nearer]] = t[nearer]
                if own_ids:
                    own[rays[nearer]] = np.isin(ids[nearer], own_ids)
        ranges += self.config.noise * rng.standard_normal(ranges.size, dtype=np.float32)  # inf stays inf
        ranges = ranges.reshape(shape)
        return RangeImage(ranges=ranges, directions=self.directions, origin=self.origin, own_body=own.reshape(shape))
