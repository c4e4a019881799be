"""The range camera: true ranges along unit rays, and the fast path equals a full cast."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from afford.sim.camera import CameraConfig, MeshInstance, RangeCamera
from afford.sim.objects import ObjectSpec, object_mesh


def _sphere(centre, diameter=0.2):
    v, t = object_mesh(ObjectSpec("sphere", (diameter,), (0.0, 0.0)))
    return MeshInstance(v, t, np.asarray(centre, dtype=float), np.array([1.0, 0, 0, 0]))


def test_ranges_are_distances_along_the_ray_not_depth():
    config = replace(CameraConfig(), noise=0.0)
    cam = RangeCamera(config)
    # a sphere off the optical axis: the range to its nearest point is |c - o| - r
    centre = np.array([0.95, 0.15, 0.9])
    img = cam.capture([_sphere(centre)], np.random.default_rng(0))
    nearest = np.nanmin(np.where(np.isfinite(img.ranges), img.ranges, np.nan))
    expected = np.linalg.norm(centre - np.array(config.position)) - 0.1
    assert abs(nearest - expected) < 0.004  # the sphere is a 16-step mesh


def test_casting_only_near_moving_bodies_gives_the_full_image():
    from afford.sim.objects import box_mesh

    config = replace(CameraConfig(), noise=0.0)
    v, t = box_mesh((0.35, 0.5, 0.375))
    table = MeshInstance(v, t, np.array([0.75, 0.0, 0.375]), np.array([1.0, 0, 0, 0]))
    moving = [_sphere((0.6, -0.2, 0.85)), _sphere((0.9, 0.3, 0.95), 0.3)]
    fast = RangeCamera(config)
    fast.set_static([table], key="table")
    img = fast.capture(moving, np.random.default_rng(0)).ranges
    full = RangeCamera(config)
    ref = full.capture([table, *moving], np.random.default_rng(0)).ranges
    assert np.array_equal(np.isfinite(img), np.isfinite(ref))
    assert np.allclose(img[np.isfinite(img)], ref[np.isfinite(ref)], atol=1e-5)
    assert (img < np.inf).sum() > 1000


def test_noise_has_the_configured_spread():
    config = replace(CameraConfig(), noise=0.01)
    cam = RangeCamera(config)
    a = cam.capture([_sphere((0.9, 0.0, 0.9), 0.5)], np.random.default_rng(0)).ranges
    b = cam.capture([_sphere((0.9, 0.0, 0.9), 0.5)], np.random.default_rng(1)).ranges
    hit = np.isfinite(a)
    diff = a[hit] - b[hit]
    assert 0.012 < diff.std() < 0.016  # sqrt(2) * 0.01
