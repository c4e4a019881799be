"""Grid features of a whole range image (thesis 5.3.1): features/grid.py."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features.detect import RangeImage
from afford.features.grid import (
    N_CELL_FEATURES,
    GridSpec,
    cell_edges,
    cell_of_feature,
    feature_cells,
    grid_features,
    grid_histogram_groups,
    grid_normal_bins,
    grid_schema,
)

THETA = slice(3, 21)
PHI = slice(21, 39)


def _directions(h: int, w: int, step_deg: float = 0.75, pitch_deg: float = 0.0) -> np.ndarray:
    """Unit rays of a scanner looking along +x, pitched down by pitch_deg; rows go down,
    columns to the robot's right (-y), as in sim/camera.py."""
    step = np.radians(step_deg)
    cols = np.tan((np.arange(w) - (w - 1) / 2) * step)
    rows = np.tan((np.arange(h) - (h - 1) / 2) * step)
    p = np.radians(pitch_deg)
    forward = np.array([np.cos(p), 0.0, -np.sin(p)])
    right = np.array([0.0, -1.0, 0.0])
    down = np.cross(forward, right)
    d = forward + cols[None, :, None] * right + rows[:, None, None] * down
    return d / np.linalg.norm(d, axis=2, keepdims=True)


def _plane_ranges(d: np.ndarray, normal, offset: float) -> np.ndarray:
    """Ranges from the origin to the plane normal . p = offset (inf where the ray misses)."""
    dot = d @ np.asarray(normal, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = offset / dot
    return np.where(np.isfinite(t) & (t > 0), t, np.inf)


def _image(ranges: np.ndarray, d: np.ndarray) -> RangeImage:
    return RangeImage(ranges=ranges, directions=d, origin=np.zeros(3))


def _cells(f: np.ndarray, spec: GridSpec) -> np.ndarray:
    return f.reshape(spec.layers, spec.cells, spec.cells, N_CELL_FEATURES)


def _wall(h: int = 60, w: int = 60) -> RangeImage:
    d = _directions(h, w)
    return _image(_plane_ranges(d, (1.0, 0.0, 0.0), 2.0), d)  # the plane x = 2 m


# --- schema -------------------------------------------------------------------------


def test_schema_sizes_and_names():
    default = grid_schema(GridSpec())
    assert len(default) == 3900
    big = grid_schema(GridSpec(cells=30, layers=1))
    assert len(big) == 35100
    for schema in (default, big):
        assert len(set(schema.names)) == len(schema)
        assert set(schema.channels) == {"range", "shape"}
    assert default.names[:4] == ("l0_r0_c0_min", "l0_r0_c0_max", "l0_r0_c0_mean", "l0_r0_c0_theta_00")
    i = default.index("l3_r2_c4_phi_17")
    assert default.channels[i] == "shape"
    assert default.channels[default.index("l1_r4_c0_mean")] == "range"
    assert len(default.channel_indices("range")) == 3 * 100


def test_histogram_groups_and_cells_match_names():
    spec = GridSpec(cells=3, layers=2)
    schema = grid_schema(spec)
    groups = grid_histogram_groups(spec)
    assert len(groups) == 2 * spec.n_cells
    covered = np.zeros(len(schema), dtype=int)
    for start, stop in groups:
        assert stop - start == 18
        names = schema.names[start:stop]
        assert names[0].endswith(("theta_00", "phi_00")) and names[-1].endswith(("theta_17", "phi_17"))
        assert len({n.rsplit("_", 2)[0] for n in names}) == 1  # one cell, one angle
        covered[start:stop] += 1
    assert np.all(covered[np.asarray(schema.channels) == "shape"] == 1)
    assert np.all(covered[np.asarray(schema.channels) == "range"] == 0)

    cells = feature_cells(spec)
    assert cells.shape == (len(schema), 3)
    for index in (0, 40, 77, len(schema) - 1):
        layer, row, col, name = cell_of_feature(spec, index)
        assert schema.names[index] == f"l{layer}_r{row}_c{col}_{name}"
        assert tuple(cells[index]) == (layer, row, col)
    with pytest.raises(IndexError):
        cell_of_feature(spec, len(schema))


# --- the vector ---------------------------------------------------------------------


@pytest.mark.parametrize("spec", [GridSpec(), GridSpec(cells=30, layers=1)])
def test_vector_length_dtype_finite(spec):
    d = _directions(360, 360, step_deg=0.25, pitch_deg=20.0)
    ranges = np.minimum(_plane_ranges(d, (0, 0, 1.0), -0.3), _plane_ranges(d, (1.0, 0, 0), 2.0))
    ranges = ranges + np.random.default_rng(0).normal(0.0, 0.003, ranges.shape)
    image = _image(ranges, d)
    before = ranges.copy()
    f = grid_features(image, spec)
    assert f.dtype == np.float32
    assert f.shape == (len(grid_schema(spec)),)
    assert np.all(np.isfinite(f))
    np.testing.assert_array_equal(image.ranges, before)  # not mutated
    hist = _cells(f, spec)
    sums = hist[..., THETA].sum(axis=-1)
    np.testing.assert_allclose(sums, 1.0, atol=1e-5)  # every cell sees the scene
    np.testing.assert_allclose(hist[..., PHI].sum(axis=-1), 1.0, atol=1e-5)


def test_wall_facing_scanner():
    spec = GridSpec(cells=5, layers=2)
    image = _wall()
    cells = _cells(grid_features(image, spec), spec)
    r = image.ranges
    assert np.all(cells[..., 0] <= cells[..., 2] + 1e-6)
    assert np.all(cells[..., 2] <= cells[..., 1] + 1e-6)
    assert np.all(cells[..., 0] >= 2.0 - 1e-6)  # the wall is 2 m ahead
    assert np.all(cells[..., 1] <= r.max() + 1e-6)
    # the centre cell of layer 0 holds the nearest pixels; corners are farther
    assert cells[0, 2, 2, 0] < cells[0, 0, 0, 0]
    np.testing.assert_allclose(cells[0, 0, 0, 1], r[:12, :12].max(), rtol=1e-6)
    np.testing.assert_allclose(cells[0, 0, 0, 2], r[:12, :12].mean(), rtol=1e-6)
    # normal (-1, 0, 0): polar angle 90 (bin 9), heading 180 (bin 9), in every cell
    assert np.all(cells[..., THETA][..., 9] == 1.0)
    assert np.all(cells[..., PHI][..., 9] == 1.0)


def test_normals_face_the_scanner_whatever_the_pixel_order():
    wall = _wall()
    spec = GridSpec(cells=3, layers=1)
    for flip in ((slice(None), slice(None, None, -1)), (slice(None, None, -1), slice(None))):
        mirrored = _image(wall.ranges[flip], wall.directions[flip])  # cross product flips
        cells = _cells(grid_features(mirrored, spec), spec)
        assert np.all(cells[..., THETA][..., 9] == 1.0)
        assert np.all(cells[..., PHI][..., 9] == 1.0)  # heading 180, back at the scanner
    floor_d = _directions(40, 40, pitch_deg=60.0)[:, ::-1]
    floor = _image(_plane_ranges(floor_d, (0.0, 0.0, 1.0), -0.3), floor_d)
    assert np.all(_cells(grid_features(floor, spec), spec)[..., THETA][..., 0] == 1.0)


def test_oblique_wall_heading_bin():
    d = _directions(60, 60)
    heading = np.radians(140.0)
    normal = (np.cos(heading), np.sin(heading), 0.0)  # faces the scanner, 140 deg from +x
    spec = GridSpec(cells=3, layers=1)
    cells = _cells(grid_features(_image(_plane_ranges(d, normal, -2.0), d), spec), spec)
    assert np.all(cells[..., PHI][..., 7] == 1.0)  # 140 / 20 = bin 7
    assert np.all(cells[..., THETA][..., 9] == 1.0)


def test_floor_normals_point_up():
    d = _directions(60, 60, pitch_deg=60.0)  # every ray meets the floor
    ranges = _plane_ranges(d, (0.0, 0.0, 1.0), -0.3)  # z = -0.3 below the scanner
    assert np.all(np.isfinite(ranges))
    spec = GridSpec(cells=4, layers=2)
    cells = _cells(grid_features(_image(ranges, d), spec), spec)
    assert np.all(cells[..., THETA][..., 0] == 1.0)  # theta = 0: facing up
    np.testing.assert_allclose(cells[..., PHI].sum(axis=-1), 1.0, atol=1e-6)


def test_normal_bins_cover_whole_image_but_first_n():
    image = _wall(30, 40)
    has, tb, pb = grid_normal_bins(image, n=5)
    assert has.shape == (30, 40)
    assert not has[:5].any() and not has[:, :5].any()
    assert has[5:, 5:].all()
    assert np.all(tb[has] == 9) and np.all(pb[has] == 9)
    assert np.all(tb[~has] == -1)


def test_near_box_changes_centre_not_corners():
    spec = GridSpec()  # 5 x 5, 4 layers
    wall = _wall(100, 100)
    near = wall.ranges.copy()
    near[40:60, 40:60] = 0.8  # a patch facing the scanner at 0.8 m, in the centre cell
    base = _cells(grid_features(wall, spec), spec)
    boxed = _cells(grid_features(_image(near, wall.directions), spec), spec)
    assert boxed[0, 2, 2, 0] == pytest.approx(0.8)
    assert base[0, 2, 2, 0] > 1.9
    assert boxed[0, 2, 2, 2] < base[0, 2, 2, 2]
    np.testing.assert_array_equal(boxed[:, 0, 0], base[:, 0, 0])
    np.testing.assert_array_equal(boxed[:, 4, 4], base[:, 4, 4])
    np.testing.assert_array_equal(boxed[:, 0, 4], base[:, 0, 4])
    np.testing.assert_array_equal(boxed[:, 4, 0], base[:, 4, 0])


def test_misses_count_as_max_range():
    spec = GridSpec(cells=2, layers=1, max_range=3.5)
    wall = _wall(40, 40)
    ranges = wall.ranges.copy()
    ranges[:20, :] = np.inf   # top half: nothing there
    ranges[20:, 20:] = 9.0    # a far surface beyond max_range
    f = grid_features(_image(ranges, wall.directions), spec)
    assert np.all(np.isfinite(f))
    cells = _cells(f, spec)
    for col in (0, 1):
        np.testing.assert_array_equal(cells[0, 0, col, :3], [3.5, 3.5, 3.5])
        assert np.all(cells[0, 0, col, 3:] == 0.0)  # no normals of misses
    np.testing.assert_array_equal(cells[0, 1, 1, :3], [3.5, 3.5, 3.5])
    assert cells[0, 1, 1, THETA].sum() == pytest.approx(1.0)  # far surfaces keep their normals
    assert cells[0, 1, 0, 0] >= 2.0 and cells[0, 1, 0, 1] < 3.5


def test_layer_zero_is_the_unshifted_grid():
    d = _directions(90, 90, pitch_deg=20.0)
    ranges = np.minimum(_plane_ranges(d, (0, 0, 1.0), -0.3), _plane_ranges(d, (1.0, 0, 0), 2.0))
    ranges[30:50, 35:55] = 1.1
    image = _image(ranges, d)
    four = _cells(grid_features(image, GridSpec(cells=5, layers=4)), GridSpec(cells=5, layers=4))
    one = _cells(grid_features(image, GridSpec(cells=5, layers=1)), GridSpec(cells=5, layers=1))
    np.testing.assert_allclose(four[0], one[0], rtol=1e-6, atol=1e-7)
    assert not np.allclose(four[1], four[0])


def test_shifted_layer_cells_and_border():
    spec = GridSpec(cells=2, layers=2)
    rows, cols = cell_edges(spec, (40, 40))
    np.testing.assert_array_equal(rows, [[0, 20, 40], [10, 30, 40]])
    np.testing.assert_array_equal(cols, rows)

    wall = _wall(40, 40)
    straddle = wall.ranges.copy()
    straddle[17:23, 17:23] = 1.0  # across layer 0's cell corner, inside layer 1's cell (0, 0)
    cells = _cells(grid_features(_image(straddle, wall.directions), spec), spec)
    assert np.all(cells[0, :, :, 0] == pytest.approx(1.0))  # every layer-0 cell sees a part
    assert cells[1, 0, 0, 0] == pytest.approx(1.0)
    assert cells[1, 0, 1, 0] > 1.9 and cells[1, 1, 0, 0] > 1.9 and cells[1, 1, 1, 0] > 1.9

    corner = wall.ranges.copy()
    corner[2:6, 2:6] = 1.0  # in the strip before layer 1's first edge
    cells = _cells(grid_features(_image(corner, wall.directions), spec), spec)
    assert cells[0, 0, 0, 0] == pytest.approx(1.0)
    assert np.all(cells[1, ..., 0] > 1.9)  # no layer-1 cell covers it

    # the clipped last cell of layer 1 (rows and columns 30..40) is a quarter of a cell
    far = wall.ranges.copy()
    far[30:, 30:] = 3.0
    cells = _cells(grid_features(_image(far, wall.directions), spec), spec)
    np.testing.assert_array_equal(cells[1, 1, 1, :3], [3.0, 3.0, 3.0])


def test_tiny_image_has_empty_cells_not_nan():
    spec = GridSpec(cells=5, layers=4)
    image = _wall(8, 12)  # fewer rows than cells * layers; some cells get no pixels
    f = grid_features(image, spec)
    assert f.shape == (3900,) and np.all(np.isfinite(f))
    cells = _cells(f, spec)
    rows, cols = cell_edges(spec, (8, 12))
    area = np.diff(rows, axis=1)[:, :, None] * np.diff(cols, axis=1)[:, None, :]
    assert np.any(area == 0)
    assert np.all(cells[area == 0][:, :3] == spec.max_range)
    assert np.all(cells[area > 0][:, 0] < 2.1)
