"""The simulated range camera (thesis section 4.2), ray-cast with Open3D.

A grid of ``width`` x ``height`` rays leaves the camera centre ``step_deg`` apart in both
directions; each returns the distance to the first surface it meets, plus Gaussian noise.
Rays are built here with unit length, so Open3D's ``t_hit`` is the range along the ray
(its own pinhole rays are not unit length: their ``t_hit`` is depth). Misses are ``inf``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import open3d as o3d

from features import RangeImage

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
        self.origin = origin
        rays = np.concatenate([np.broadcast_to(origin, self.directions.shape), self.directions], axis=2)
        self._rays = o3d.core.Tensor(rays.reshape(-1, 6).astype(np.float32))

    def capture(self, meshes: list[MeshInstance], rng: np.random.Generator) -> RangeImage:
        scene = o3d.t.geometry.RaycastingScene()
        own_ids = []
        for m in meshes:
            world = m.vertices @ _rotation(m.quaternion).T + m.position
            gid = scene.add_triangles(o3d.core.Tensor(world.astype(np.float32)),
                                      o3d.core.Tensor(m.triangles.astype(np.uint32)))
            if m.own_body:
                own_ids.append(gid)
        hits = scene.cast_rays(self._rays, nthreads=self.threads)
        shape = (self.config.height, self.config.width)
        ranges = hits["t_hit"].numpy().astype(np.float64).reshape(shape)
        ids = hits["geometry_ids"].numpy().reshape(shape)
        noise = rng.normal(0.0, self.config.noise, size=shape)
        ranges = np.where(np.isfinite(ranges), ranges + noise, np.inf)
        own = np.isin(ids, own_ids) if own_ids else np.zeros(shape, dtype=bool)
        return RangeImage(ranges=ranges, directions=self.directions, origin=self.origin, own_body=own)
