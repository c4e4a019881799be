"""The chapter-5 robot in pinned traverse worlds: what blocks it, what it pushes, climbs and crosses.

Every outcome here is PhysX's; the robot judges it from its own encoders and IMU.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from afford.features.errors import DataError
from afford.sim.layout import LayoutError
from afford.sim.traverse import (
    ROTATIONS, Gap, Item, Ramp, TraverseLayout, TraverseWorld, check_layout, layout_toml, parse_layout,
    sample_body, sample_clutter, sample_gap, sample_ramp,
)


def go(layout: TraverseLayout, rotate: float = 0.0, seed: int = 0):
    world = TraverseWorld(layout, np.random.default_rng(seed))
    odometry = world.move(rotate)
    return odometry, world.truth()


def one(text: str) -> TraverseLayout:
    return parse_layout(text, "test.toml")


# -- objects ------------------------------------------------------------------------------------
def test_a_heavy_box_in_the_path_blocks_going_forward():
    odo, truth = go(one('[[object]]\nshape = "box"\nsize = [0.3, 0.3, 0.3]\nposition = [0.7, 0.0]\n'))
    assert not odo.success
    assert odo.displacement_m < 0.5
    assert truth["contact"] and truth["touched_objects"] == [0]
    assert truth["end"]["x"] < 0.45  # it really stopped at the box (ground truth agrees)


def test_a_sphere_in_the_path_is_pushed_away_and_the_robot_traverses():
    odo, truth = go(one('[[object]]\nshape = "sphere"\nsize = [0.25]\nposition = [0.6, 0.0]\n'))
    assert odo.success
    assert truth["contact"]
    start, end = truth["objects"][0]["start"], truth["objects"][0]["end"]
    assert end[0] - start[0] > 0.2


def test_a_lying_cylinder_rolls_across_its_axis_but_not_along_it():
    across, _ = go(TraverseLayout(items=(Item("lying-cylinder", (0.2, 0.6), (0.6, 0.0), yaw=90.0),)))
    along, _ = go(TraverseLayout(items=(Item("lying-cylinder", (0.2, 0.6), (0.7, 0.0), yaw=0.0),)))
    assert across.success
    assert not along.success


def test_a_box_hanging_below_the_robots_top_blocks_it_and_one_above_lets_it_pass():
    low, low_truth = go(TraverseLayout(items=(Item("box", (0.2, 0.6, 0.1), (0.6, 0.0), z=0.40, fixed=True),)))
    high, high_truth = go(TraverseLayout(items=(Item("box", (0.2, 0.6, 0.1), (0.6, 0.0), z=0.52, fixed=True),)))
    assert not low.success and low_truth["contact"]
    assert high.success and not high_truth["contact"]


# -- ramps and gaps -----------------------------------------------------------------------------
def test_a_gentle_ramp_head_on_is_climbed_and_a_steep_one_is_not():
    gentle, gentle_truth = go(TraverseLayout(ramps=(Ramp((0.4, 0.0), 0.0, 1.0, 1.5, 5.0),)))
    steep, _ = go(TraverseLayout(ramps=(Ramp((0.4, 0.0), 0.0, 1.0, 1.5, 25.0),)))
    assert gentle.success
    assert gentle_truth["end"]["z"] > 0.015  # it is up on the ramp
    assert not steep.success


def test_a_narrow_gap_is_crossed_and_a_wide_one_is_not():
    narrow, narrow_truth = go(one("[[gap]]\ndistance = 0.1\nwidth = 0.08\n"))
    wide, wide_truth = go(one("[[gap]]\ndistance = 0.1\nwidth = 0.40\n"))
    assert narrow.success and not narrow_truth["fell"]
    assert narrow_truth["end"]["x"] > 0.65
    assert not wide.success
    assert wide_truth["end"]["x"] < 0.5  # it fell in or stopped at the edge


# -- the behaviours in an empty world -----------------------------------------------------------
@pytest.mark.parametrize("rotate", ROTATIONS)
def test_every_behaviour_succeeds_in_an_empty_world(rotate):
    odo, truth = go(TraverseLayout(), rotate)
    assert odo.success, odo
    assert abs(truth["end"]["yaw"] - rotate) < 1.0
    moved = math.hypot(truth["end"]["x"], truth["end"]["y"])
    assert 0.65 <= moved <= 0.75
    heading = math.degrees(math.atan2(truth["end"]["y"], truth["end"]["x"]))
    assert abs(heading - rotate) < 5.0  # it drove off in the direction it turned to
    assert not truth["contact"] and not truth["fell"]


def test_odometry_is_the_robots_reading_not_ground_truth():
    """Against a wall the encoders count where the robot really stopped (no wheel spin)."""
    odo, truth = go(TraverseLayout(items=(Item("box", (0.2, 1.0, 0.5), (0.6, 0.0), fixed=True),)))
    assert not odo.success
    assert odo.travelled_m == pytest.approx(truth["end"]["x"], abs=0.02)


# -- the scanner ---------------------------------------------------------------------------------
def test_the_scan_of_an_empty_world_sees_the_floor_below_the_horizon_only():
    image = TraverseWorld(TraverseLayout(), np.random.default_rng(0)).scan()
    assert image.ranges.shape == (360, 360)
    assert image.directions.shape == (360, 360, 3)
    np.testing.assert_allclose(np.linalg.norm(image.directions, axis=-1), 1.0, atol=1e-6)
    lower, upper = image.ranges[200:], image.ranges[:170]
    assert np.isfinite(lower[:, 60:300]).mean() > 0.9
    assert not np.isfinite(upper).any()
    floor = image.points()[np.isfinite(image.ranges)]
    assert np.abs(floor[:, 2]).max() < 0.03  # every hit lies on the floor (range noise 3 mm)


def test_a_box_in_front_shows_nearer_ranges_in_the_image_centre():
    empty = TraverseWorld(TraverseLayout(), np.random.default_rng(0)).scan()
    box = TraverseWorld(TraverseLayout(items=(Item("box", (0.3, 0.3, 0.3), (1.0, 0.0)),)),
                        np.random.default_rng(0)).scan()
    centre = (slice(175, 230), slice(165, 195))
    near, far = np.nan_to_num(box.ranges[centre], posinf=9.0), np.nan_to_num(empty.ranges[centre], posinf=9.0)
    assert np.all(near <= far + 0.02)       # nothing got farther
    assert (near < far - 0.1).sum() > 100   # the box's front face, much nearer than the floor behind it
    assert near.min() < 0.9


def test_the_same_seed_gives_byte_identical_scans_and_odometry():
    layout = sample_clutter(np.random.default_rng(3))
    a = TraverseWorld(layout, np.random.default_rng(11))
    b = TraverseWorld(layout, np.random.default_rng(11))
    assert a.scan().ranges.tobytes() == b.scan().ranges.tobytes()
    oa = TraverseWorld(layout, np.random.default_rng(11)).move(20.0)
    ob = TraverseWorld(layout, np.random.default_rng(11)).move(20.0)
    assert oa == ob
    assert sample_clutter(np.random.default_rng(3)) == layout


# -- layouts ---------------------------------------------------------------------------------------
def test_layouts_round_trip_through_toml():
    layout = TraverseLayout(items=(Item("box", (0.1, 0.2, 0.3), (0.8, 0.1), 30.0),
                                   Item("box", (0.1, 0.1, 0.1), (0.8, -0.3), 0.0, z=0.5, fixed=True)),
                            ramps=(Ramp((0.6, 0.2), -20.0, 0.8, 1.2, 7.5),), gaps=(Gap(0.5, 0.2, 15.0),))
    assert parse_layout(layout_toml(layout)) == layout
    assert TraverseLayout.from_dict(layout.to_dict()) == layout


@pytest.mark.parametrize("text, words", [
    ('[[object]]\nshape = "cone"\nsize = [0.1]\nposition = [1, 0]\n', "object 0: unknown shape"),
    ('[[object]]\nshape = "box"\nsize = [0.1]\nposition = [1, 0]\n', "object 0"),
    ('[[object]]\nshape = "box"\nsize = [0.1, 0.1, 0.1]\nposition = [1, 0]\nz = 0.3\n', "fixed"),
    ("[[ramp]]\nposition = [1, 0]\nslope = 80\n", "ramp 0"),
    ("[[gap]]\ndistance = 0.3\n", "gap 0: missing 'width'"),
    ("[[gap]]\ndistance = 0.3\nwidth = 0.1\n[[gap]]\ndistance = 0.8\nwidth = 0.1\n", "at most one gap"),
    ("[[hole]]\nwidth = 1\n", "unknown table"),
    ("[[gap]]\ndistance = 0.3\nwidth = 0.1\ncolour = 1\n", "unknown key 'colour'"),
])
def test_layout_mistakes_are_one_sentence_naming_file_and_entry(text, words):
    with pytest.raises(LayoutError) as err:
        parse_layout(text, "bad.toml")
    message = str(err.value)
    assert message.startswith("bad.toml") and words in message and "\n" not in message


def test_check_layout_refuses_what_overlaps_the_robots_start():
    with pytest.raises(ValueError, match="object 0"):
        check_layout(TraverseLayout(items=(Item("box", (0.3, 0.3, 0.3), (0.2, 0.0)),)))
    with pytest.raises(ValueError, match="gap 0"):
        check_layout(TraverseLayout(gaps=(Gap(0.1, 0.2, 70.0),)))
    check_layout(TraverseLayout(items=(Item("box", (0.3, 0.3, 0.1), (0.1, 0.0), z=0.6, fixed=True),)))


def test_rectangle_overlap_agrees_with_corners_and_edges_near_and_far():
    """The overlap test (bounding circles first, then separating axes) against the
    classic oracle: two rectangles meet iff a corner of one lies in the other or two edges cross."""
    from afford.sim.traverse import _corners, _rects_overlap

    def d(a, b, c):  # which side of a->b the point c lies on
        return (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])

    def inside(p, quad):  # quad counter-clockwise
        return all(d(quad[k], quad[(k + 1) % 4], p) >= 0 for k in range(4))

    def cross(p1, p2, q1, q2):
        return d(p1, p2, q1) * d(p1, p2, q2) < 0 and d(q1, q2, p1) * d(q1, q2, p2) < 0

    rng = np.random.default_rng(3)
    met = 0
    for _ in range(1500):
        a = (tuple(rng.uniform(-1, 1, 2)), tuple(rng.uniform(0.02, 0.5, 2)), float(rng.uniform(0, 360)))
        b = (tuple(rng.uniform(-1, 1, 2)), tuple(rng.uniform(0.02, 0.5, 2)), float(rng.uniform(0, 360)))
        margin = float(rng.choice([0.0, 0.05]))
        if rng.random() < 0.5:  # near: the bounding circles (with the margin) just touch or barely overlap
            reach = sum(np.hypot(*(np.asarray(r[1]) + margin / 2)) for r in (a, b)) * rng.uniform(0.9, 1.01)
            th = rng.uniform(0, 2 * np.pi)
            b = ((a[0][0] + reach * np.cos(th), a[0][1] + reach * np.sin(th)), b[1], b[2])
        qa = _corners(a[0], np.asarray(a[1]) + margin / 2, a[2])
        qb = _corners(b[0], np.asarray(b[1]) + margin / 2, b[2])
        truth = (any(inside(p, qb) for p in qa) or any(inside(p, qa) for p in qb)
                 or any(cross(qa[i], qa[(i + 1) % 4], qb[j], qb[(j + 1) % 4]) for i in range(4) for j in range(4)))
        assert _rects_overlap(a, b, margin) == truth, (a, b, margin)
        met += truth
    assert 150 < met < 1350  # both answers are exercised, near pairs and far ones


@pytest.mark.parametrize("sampler", [sample_clutter, sample_body, sample_ramp, sample_gap])
def test_sampled_layouts_are_valid_starts(sampler):
    rng = np.random.default_rng(5)
    for _ in range(20):
        check_layout(sampler(rng))


def test_layouts_off_the_floor_or_with_overlapping_ramps_are_refused():
    with pytest.raises(ValueError, match="lies off the floor"):
        check_layout(TraverseLayout(items=(Item("box", (0.3, 0.3, 0.3), (1000.0, 0.0)),)))
    with pytest.raises(ValueError, match="ramps 0 and 1 overlap"):
        check_layout(TraverseLayout(ramps=(Ramp((0.6, 0.0), 0.0, 1.0, 1.0, 10.0), Ramp((0.7, 0.1), 0.0, 1.0, 1.0, 5.0))))


# -- traverse-room (chapter 6): one walled room, the robot somewhere in it --------------------

def test_the_room_stays_and_the_robot_moves_and_another_room_differs():
    from afford.sim.registry import make_scene
    from afford.sim.scenes.traverse_room import room_items

    scene = make_scene("traverse-room")
    a, b = (scene.sample(np.random.default_rng(s)) for s in (1, 2))
    assert len(a.items) == len(b.items) == len(room_items(0)) == 54
    dist = lambda lay, i, j: np.hypot(*np.subtract(lay.items[i].position, lay.items[j].position))
    # the same room seen from two places: distances between its things are kept, positions are not
    assert dist(a, 30, 40) == pytest.approx(dist(b, 30, 40), abs=1e-3)
    assert a.items[30].position != b.items[30].position
    assert room_items(1)[30].position != room_items(0)[30].position
    assert make_scene("traverse-room", room=1).describe()["room"] == 1


def test_a_harder_room_holds_more_smaller_things_and_its_artefacts_rebuild_it(tmp_path):
    import afford
    from afford.sim.registry import make_scene
    from tests.clitools import fails, ok

    harder = make_scene("traverse-room", clutter=60, size_min=0.1, size_max=0.3)
    loose = [it for it in harder.items() if not it.fixed]
    assert len(loose) == 60 and all(0.1 <= v <= 0.3 for it in loose for v in it.size)
    # robot-frame layouts of it hold every wall and loose object
    assert len(harder.sample(np.random.default_rng(3)).items) == len(harder.items())
    # the default room is described as before (artefacts keep their bytes); a harder one says so
    assert "clutter" not in make_scene("traverse-room").describe()
    assert make_scene("traverse-room", **harder.options_from(harder.describe())).items() == harder.items()
    ok(["explore", "--scene", "traverse-room", "--clutter", "60", "--size-min", "0.1", "--size-max", "0.3",
        "--episodes", "1", "-o", str(tmp_path / "h.afford")])
    assert afford.load_interactions(str(tmp_path / "h.afford")).scene["clutter"] == 60
    assert "--clutter does not apply to scene 'room'" in " ".join(
        fails(["explore", "--scene", "room", "--clutter", "5", "-o", str(tmp_path / "x.afford")], 2).replace("│", " ").split())
    assert "loose objects must satisfy 0.05 <= size-min" in fails(
        ["explore", "--scene", "traverse-room", "--size-min", "0.03", "-o", str(tmp_path / "x.afford")])
    assert not (tmp_path / "x.afford").exists()


def test_a_wall_ahead_stops_the_robot_and_open_floor_does_not():
    from afford.sim.registry import make_scene
    from afford.sim.scenes.traverse_room import in_robot_frame, room_items

    scene = make_scene("traverse-room")
    walls = tuple(it for it in room_items(0) if it.fixed)
    forward = scene.behaviors[0]
    assert forward.name == "go-forward"
    success = list(scene.results).index("success")
    near_wall = in_robot_frame(walls, 2.45, 0.0, 0.0)   # the wall's face 50 cm ahead
    in_the_middle = in_robot_frame(walls, 0.0, 0.0, 0.0)
    blocked = forward(scene.build(near_wall, np.random.default_rng(0)), None, np.zeros(0))
    free = forward(scene.build(in_the_middle, np.random.default_rng(0)), None, np.zeros(0))
    assert blocked.result != success and free.result == success


# -- traverse-one (5.6.4.1): one object of the chosen shapes -------------------------------------

def test_one_object_of_the_chosen_shapes_stands_in_front_of_the_robot():
    from afford.sim.registry import make_scene

    scene = make_scene("traverse-one", shapes="sphere,box")
    assert scene.shapes == ("box", "sphere") and scene.describe()["shapes"] == ["box", "sphere"]
    layouts = [scene.sample(np.random.default_rng(s)) for s in range(40)]
    assert all(len(lay.items) == 1 for lay in layouts)
    assert {lay.items[0].shape for lay in layouts} == {"box", "sphere"}
    assert all(0.35 <= lay.items[0].position[0] <= 0.95 and abs(lay.items[0].position[1]) <= 0.3 for lay in layouts)
    again = make_scene("traverse-one", **scene.options_from(scene.describe()))
    assert again.shapes == scene.shapes
    with pytest.raises(DataError, match="unknown shape 'cube'; the shapes are box, cylinder, lying-cylinder, sphere"):
        make_scene("traverse-one", shapes="box,cube")


# -- traverse-furniture (5.6.4.2): tables and a chair of fixed boxes -----------------------------

def _go_forward_through(items) -> bool:
    from afford.sim.registry import make_scene
    from afford.sim.traverse import TraverseLayout

    scene = make_scene("traverse-furniture")
    layout = TraverseLayout(items=items)
    scene.check_layout(layout)
    forward = scene.behaviors[0]
    return forward(scene.build(layout, np.random.default_rng(0)), None, np.zeros(0)).result == list(scene.results).index("success")


def test_the_robot_drives_under_a_high_table_between_its_legs_but_not_under_a_low_one():
    from afford.sim.furniture import place, wooden_table

    # the table's long side across the path: 1.2 m between the legs, the top 0.7 m or 0.4 m up
    assert _go_forward_through(place(wooden_table(0.7, 1.2, 0.70), 0.75, 0.0, 0.0))
    assert not _go_forward_through(place(wooden_table(0.7, 1.2, 0.40), 0.75, 0.0, 0.0))
    # a leg straight ahead stops it, however high the top
    assert not _go_forward_through(place(wooden_table(0.7, 1.2, 0.70), 0.75 + 0.29, 0.56, 0.0))


def test_an_iron_tables_bars_stop_the_robot_unless_they_are_above_it():
    from afford.sim.furniture import iron_table, place

    assert not _go_forward_through(place(iron_table(0.7, 1.2, 0.75, bar=0.15), 0.75, 0.0, 0.0))
    assert _go_forward_through(place(iron_table(0.7, 1.2, 0.75, bar=0.60), 0.75, 0.0, 0.0))


def test_a_chairs_seat_below_the_robots_top_stops_it():
    from afford.sim.furniture import chair, place

    assert not _go_forward_through(place(chair(), 0.6, 0.0, 90.0))
    assert _go_forward_through(place(chair(), 0.6, 0.7, 90.0))  # beside the path


def test_explored_ramps_reach_the_slopes_that_stop_the_robot_on_an_oblique_ramp():
    """Table 5.1 raises a ramp to 40 degrees, and an oblique ramp stops the robot only past
    25-38: exploration must meet steep oblique ramps, or the model cannot place that boundary."""
    rng = np.random.default_rng(11)
    ramps = [sample_ramp(rng).ramps[0] for _ in range(400)]
    slopes = np.array([r.slope for r in ramps])
    assert slopes.min() >= 2.0 and slopes.max() <= 40.0
    steep_oblique = [r for r in ramps if r.slope > 32.0 and 30.0 <= abs(r.yaw) <= 60.0]
    assert len(steep_oblique) >= 10
