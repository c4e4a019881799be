"""The grasp scene (thesis chapter 9): what PhysX makes of the three-finger hand's behaviours
on pinned layouts, and what the robot perceives of it (contact-point features)."""

from __future__ import annotations

import numpy as np
import pytest

from afford.features.contact_point import N_CONTACT_FEATURES, contact_point_schema
from afford.sim.explore import interact, run_episode
from afford.sim.objects import ObjectSpec
from afford.sim.registry import make_scene

SCENE = make_scene("grasp")
NAMES = [b.name for b in SCENE.behaviors]
S = contact_point_schema()


def _act(spec: ObjectSpec, behaviour: str, alpha: float):
    world = SCENE.build([spec], np.random.default_rng(0))
    f = world.perceive()
    assert f.shape == (1, N_CONTACT_FEATURES)
    step = interact(world, SCENE.behaviors[NAMES.index(behaviour)], 0, np.array([alpha]), before=f)
    return SCENE.outcomes[step.outcomes[0]], step.before[0], step.after[0]


def test_contact_point_schema_has_the_thesis_six_channels():
    assert len(S) == 25
    counts = {ch: S.channels.count(ch) for ch in dict.fromkeys(S.channels)}
    assert counts == {"visibility": 1, "cp": 3, "border": 4, "patch": 4, "normal": 12, "touch": 1}
    assert S.names[S.role("height")] == "cp_z"


def test_the_contact_point_is_the_near_side_of_the_object_and_its_borders_span_it():
    spec = ObjectSpec("box", (0.16, 0.20, 0.10), (0.75, 0.05), 0.0)
    f = SCENE.build([spec], np.random.default_rng(1)).perceive()[0]
    x, y, z = (f[S.index(f"cp_{a}")] for a in "xyz")
    assert 0.67 - 0.01 <= x < 0.75  # on the half nearer the robot (the box spans x 0.67..0.83)
    assert -0.05 <= y <= 0.15 and 0.75 < z <= 0.86
    across = f[S.index("border_left")] + f[S.index("border_right")]
    assert 0.10 < across < 0.24  # the scan across the image spans about the box's 20 cm width
    assert f[S.index("touch")] == 0.0
    normals = f[[S.index(f"normal_down_{a}") for a in "xyz"]]
    assert np.linalg.norm(normals) == pytest.approx(1.0, abs=1e-6)


def test_a_small_box_is_power_grasped_and_lifted_face_on_and_the_hand_feels_it():
    outcome, before, after = _act(ObjectSpec("box", (0.08, 0.08, 0.08), (0.70, 0.0), 0.0), "power-grasp", 0.0)
    assert outcome == "lifted"
    assert after[S.index("cp_z")] - before[S.index("cp_z")] > 0.15
    assert before[S.index("touch")] == 0.0 and after[S.index("touch")] == 1.0


@pytest.mark.parametrize("alpha", [-30.0, 0.0, 30.0])
def test_a_30_cm_box_is_not_lifted_from_any_side(alpha):
    outcome, before, after = _act(ObjectSpec("box", (0.30, 0.30, 0.30), (0.75, 0.0), 0.0), "power-grasp", alpha)
    assert outcome in ("dragged", "no-change")
    assert abs(after[S.index("cp_z")] - before[S.index("cp_z")]) < 0.02


def test_a_ball_is_caught_in_a_power_grasp():
    outcome, _, _ = _act(ObjectSpec("sphere", (0.09,), (0.70, 0.0)), "power-grasp", 0.0)
    assert outcome == "lifted"


@pytest.mark.parametrize("alpha", [-30.0, 30.0])
def test_a_ball_is_pinched_between_thumb_and_index_and_lifted(alpha):
    outcome, before, after = _act(ObjectSpec("sphere", (0.11,), (0.70, 0.0)), "precision-grasp", alpha)
    assert outcome == "lifted"
    assert after[S.index("touch")] == 1.0 and after[S.index("cp_z")] - before[S.index("cp_z")] > 0.15


def test_a_mug_is_pinched_and_lifted_with_its_handle_towards_the_robot():
    outcome, before, after = _act(ObjectSpec("mug", (0.09, 0.12), (0.70, 0.0), 180.0), "precision-grasp", 0.0)
    assert outcome == "lifted"
    assert after[S.index("touch")] == 1.0


def test_a_sphere_pushed_rolls_off_the_table():
    outcome, before, after = _act(ObjectSpec("sphere", (0.09,), (0.70, 0.0)), "push-object", 0.0)
    assert outcome == "fell" and after[S.index("visibility")] == 0.0


def test_after_a_grasp_open_hand_drops_and_move_hand_carries_the_object():
    world = SCENE.build([ObjectSpec("box", (0.08, 0.08, 0.08), (0.70, 0.0), 0.0)], np.random.default_rng(0))
    f = world.perceive()
    lifted = interact(world, SCENE.behaviors[NAMES.index("power-grasp")], 0, np.array([0.0]), before=f).after
    step = interact(world, SCENE.behaviors[NAMES.index("move-hand")], 0, np.array([90.0]), before=lifted)
    moved = step.after
    carried = step.truth_after[0].position - step.truth_before[0].position
    assert carried[1] == pytest.approx(0.10, abs=0.02) and abs(carried[0]) < 0.02  # 10 cm to the left, in hand
    assert moved[0, S.index("cp_y")] - lifted[0, S.index("cp_y")] > 0.04  # and the robot sees it go that way
    dropped = interact(world, SCENE.behaviors[NAMES.index("open-hand")], 0, np.array([0.0]), before=moved).after
    assert dropped[0, S.index("cp_z")] < moved[0, S.index("cp_z")] - 0.15
    assert dropped[0, S.index("touch")] == 0.0


def test_a_grasp_episode_replays_to_the_same_bytes():
    a, b = (run_episode(SCENE, seed=3, episode=2) for _ in range(2))
    assert a.entities.tobytes() == b.entities.tobytes() and np.array_equal(a.params, b.params)
    assert a.params.shape[1] == 1 and len(a)


def test_the_closed_fist_stands_where_the_push_assumes():
    """Index and thumb close towards each other and stop where they meet; the push aims the
    fist's front, not the palm, so the config must say where that front really is."""
    world = SCENE.build([ObjectSpec("box", (0.08, 0.08, 0.08), (0.70, 0.40), 0.0)], np.random.default_rng(0))
    cfg = world.config.hand
    world.hand.set_fingers(cfg.finger_closed)
    world.step(120)
    front = max(world.hand.fingertip(n)[0] - world.hand.position[0] for n in ("index", "middle", "thumb"))
    assert front + cfg.finger_half == pytest.approx(cfg.fist_front, abs=0.005)
    assert front == pytest.approx(cfg.pinch_reach, abs=0.005)


@pytest.mark.parametrize("alpha", [0.0, 30.0])
def test_a_push_moves_a_box_about_ten_centimetres_along_alpha(alpha):
    """push-object(alpha) is a 10 cm push (thesis 9.3.2), not the fist's length more."""
    world = SCENE.build([ObjectSpec("box", (0.10, 0.10, 0.10), (0.65, 0.0), 0.0)], np.random.default_rng(0))
    f = world.perceive()
    step = interact(world, SCENE.behaviors[NAMES.index("push-object")], 0, np.array([alpha]), before=f)
    moved = step.truth_after[0].position[:2] - step.truth_before[0].position[:2]
    assert SCENE.outcomes[step.outcomes[0]] == "dragged"
    assert 0.06 <= np.linalg.norm(moved) <= 0.14
    heading = np.degrees(np.arctan2(moved[1], moved[0]))
    assert abs(heading - alpha) < 20.0
