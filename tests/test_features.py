"""Perception: Algorithm 4 detection, normals under noise, the 43-feature vector, tracking."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features import RangeImage, RegionOfInterest, detect_objects, object_schema, perceive, track
from afford.features.normals import grid_normals, normal_angles
from afford.sim.camera import MeshInstance, RangeCamera
from afford.sim.objects import ObjectSpec, object_mesh

ROI = RegionOfInterest(x=(0.4, 1.1), y=(-0.5, 0.5), z=(0.758, 1.55))


def _table_mesh():
    from afford.sim.objects import box_mesh

    v, t = box_mesh((0.35, 0.5, 0.375))
    return MeshInstance(v, t, np.array([0.75, 0.0, 0.375]), np.array([1.0, 0, 0, 0]))


def _image(specs, noise=0.003, seed=0):
    from dataclasses import replace

    from afford.sim.camera import CameraConfig

    camera = RangeCamera(replace(CameraConfig(), noise=noise))
    meshes = [_table_mesh()]
    for s in specs:
        v, t = object_mesh(s)
        pose = s.pose(0.75)
        meshes.append(MeshInstance(v, t, np.asarray(pose.p), np.asarray(pose.q)))
    return camera.capture(meshes, np.random.default_rng(seed))


def test_schema_names_43_features_in_three_channels():
    schema = object_schema()
    assert len(schema) == 43
    assert schema.channel_names == ("visibility", "position", "shape")
    assert [len(schema.channel_indices(c)) for c in schema.channel_names] == [1, 6, 36]
    with pytest.raises(KeyError, match="no feature named"):
        schema.index("colour")


def test_two_objects_apart_are_two_detections_and_the_table_is_none():
    specs = [ObjectSpec("box", (0.12, 0.12, 0.12), (0.6, -0.2)), ObjectSpec("sphere", (0.15,), (0.8, 0.25))]
    dets = detect_objects(_image(specs), ROI)
    assert len(dets) == 2
    assert detect_objects(_image([]), ROI) == []


def test_boundary_pixels_are_dropped():
    image = _image([ObjectSpec("box", (0.2, 0.2, 0.2), (0.7, 0.0))], noise=0.0)
    det = detect_objects(image, ROI)[0]
    candidate = np.isfinite(image.ranges) & ROI.contains(image.points())
    assert det.n_pixels < candidate.sum()  # the rim went
    assert det.n_pixels > 0.6 * candidate.sum()  # but not much more


def test_position_features_match_the_object_within_a_centimetre_or_two():
    spec = ObjectSpec("box", (0.20, 0.16, 0.12), (0.7, 0.1))
    f = perceive(_image([spec]), ROI)[0]
    x_min, x_max, y_min, y_max, z_min, z_max = f[1:7]
    assert abs(x_min - 0.60) < 0.02 and abs(x_max - 0.80) < 0.02
    assert abs(z_max - 0.87) < 0.01  # the top is in full view
    assert abs(y_min - 0.02) < 0.02  # the side facing the camera


def test_shape_histograms_tell_a_box_top_from_a_sphere():
    schema = object_schema()
    elev = [i for i, n in enumerate(schema.names) if n.startswith("elevation_")]
    box = perceive(_image([ObjectSpec("box", (0.2, 0.2, 0.2), (0.7, 0.0))]), ROI)[0]
    ball = perceive(_image([ObjectSpec("sphere", (0.2,), (0.7, 0.0))]), ROI)[0]
    for f in (box, ball):
        assert f[elev].sum() == pytest.approx(1.0)
    # A box shows two faces: a flat top (elevation ~90 deg, last bin) and a vertical side (~0 deg).
    assert box[elev][-1] > 0.3 and box[elev][8:10].sum() > 0.3
    # A sphere spreads its normals over many elevations.
    assert np.count_nonzero(ball[elev] > 0.03) >= 5


def test_grid_normals_of_a_noisy_plane_point_up():
    rng = np.random.default_rng(1)
    yy, xx = np.mgrid[0:40, 0:40] * 0.005
    pts = np.stack([xx, yy, 0.75 + rng.normal(0, 0.001, xx.shape)], axis=2)
    normals = grid_normals(pts, camera=np.array([0.1, 0.1, 2.0]))
    elevation, _ = normal_angles(normals)
    assert np.median(elevation) > 80


def test_track_keeps_a_vanished_object_with_visibility_zero():
    schema = object_schema()
    a = np.zeros(len(schema)); a[0] = 1; a[1:7] = [0.5, 0.6, 0.0, 0.1, 0.75, 0.85]
    b = a.copy(); b[1:7] = [0.8, 0.9, 0.2, 0.3, 0.75, 0.85]
    known = np.stack([a, b])
    moved_b = b.copy(); moved_b[1:3] += 0.05
    out = track(known, moved_b[None, :])
    assert out[0, 0] == 0 and np.allclose(out[0, 1:], a[1:])  # a gone, last seen kept
    assert np.allclose(out[1], moved_b)


def test_track_prefers_a_visible_object_over_a_vanished_one():
    schema = object_schema()
    gone = np.zeros(len(schema)); gone[1:7] = [0.6, 0.7, 0.0, 0.1, 0.75, 0.85]           # visibility 0
    held = np.zeros(len(schema)); held[0] = 1; held[1:7] = [0.6, 0.7, 0.05, 0.15, 0.95, 1.05]  # up in the hand
    dropped = held.copy(); dropped[5:7] = [0.75, 0.85]  # it fell back, right where the other vanished
    out = track(np.stack([gone, held]), dropped[None, :])
    assert out[0, 0] == 0 and out[1, 0] == 1
    assert np.allclose(out[1], dropped)


def test_periodic_parameters_are_seen_as_sine_and_cosine():
    import numpy as np

    from afford.features import encode_parameters

    spec = [{"name": "approach", "periodic": True}, {"name": "speed"}]
    near = encode_parameters(np.array([[359.0, 0.5], [1.0, 0.5]]), spec)
    assert near.shape == (2, 3)  # an angle becomes two columns, a plain parameter stays one
    assert np.abs(near[0] - near[1]).max() < 0.04  # 359 and 1 degrees are one direction
    assert np.allclose(encode_parameters(np.array([90.0, 2.0]), spec), [1.0, 0.0, 2.0], atol=1e-12)
    assert encode_parameters(np.zeros((4, 0)), []).shape == (4, 0)
