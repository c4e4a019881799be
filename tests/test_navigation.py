"""Navigation (thesis 5.6.5): the controllers' choices, and the robot driven through a room."""

from __future__ import annotations

import json

import numpy as np
import pytest

from afford.plan.navigation import choose, priority
from tests.clitools import fails, ok

ROT = (0.0, 20.0, -20.0, 40.0, -40.0, 60.0, -60.0)


def chances(afforded: set[float]) -> list[float]:
    return [0.9 if r in afforded else 0.1 for r in ROT]


def test_the_aggressive_controller_takes_the_first_afforded_move_straight_ahead_first():
    assert priority(ROT) == [0.0, 20.0, -20.0, 40.0, -40.0, 60.0, -60.0]
    assert choose("aggressive", ROT, chances({0.0, 60.0})) == 0.0
    assert choose("aggressive", ROT, chances({-20.0, 40.0})) == -20.0
    assert choose("aggressive", ROT, chances(set())) is None


def test_the_cautious_controller_moves_in_the_mean_direction_of_the_most_neighbouring_afforded_moves():
    assert choose("cautious", ROT, chances({0.0, 20.0})) == 10.0           # a new 10-degree move
    assert choose("cautious", ROT, chances({-60.0, -40.0, -20.0, 40.0, 60.0})) == -40.0
    assert choose("cautious", ROT, chances({0.0, 40.0})) is None          # afforded, but no two neighbours
    assert choose("cautious", ROT, chances({-60.0, -40.0, 40.0, 60.0})) == 50.0  # a tie: the left run


def test_the_random_controller_ignores_the_model_and_a_bad_controller_is_refused():
    picks = {choose("random", ROT, chances(set()), rng=np.random.default_rng(s)) for s in range(60)}
    assert picks == set(ROT)
    with pytest.raises(ValueError, match="unknown controller 'bold'"):
        choose("bold", ROT, chances(set()))


@pytest.fixture(scope="module")
def model(traverse_learned):
    return traverse_learned / "model.afford"


def test_navigate_drives_the_robot_through_a_room_and_its_successes_are_real_metres(model, tmp_path):
    runs = {}
    for controller in ("cautious", "random"):
        runs[controller] = out = json.loads(ok(["navigate", str(model), "--scene", "room", "--controller", controller,
                                                "--seed", "2", "--steps", "12", "--json",
                                                "--plot", str(tmp_path / f"{controller}.png")]).stdout)
        assert out["scene"] == "room" and out["room"] == 2 and out["steps"] <= 12
        assert out["moves"] + out["looks"] == out["steps"] and out["failed_moves"] <= out["moves"]
        assert len(out["path"]) == out["moves"] + 1 and len(out["failed_at"]) == out["failed_moves"]
        # every move the robot's own odometry called a success truly carried it about 70 cm (PhysX)
        steps = np.hypot(*np.diff(np.asarray(out["path"]), axis=0).T)
        moved = [e for e in out["log"] if "rotate" in e]
        assert all(0.6 < d < 0.8 for d, e in zip(steps, moved) if e["success"])
        assert out["distance_m"] == pytest.approx(float(steps.sum()), abs=0.01)
        assert out["stuck"] == (out["stuck_because"] is not None)
        # a heading that failed is not tried again before a move succeeds
        tried = []
        for e in moved:
            aim = e["heading"] + e["rotate"]
            assert all(abs((aim - h + 180) % 360 - 180) >= 10 for h in tried), (aim, tried)
            tried = [] if e["success"] else tried + [aim]
        assert (tmp_path / f"{controller}.png").read_bytes()[:4] == b"\x89PNG"
    # the same seed, the same run
    again = json.loads(ok(["navigate", str(model), "--controller", "random", "--seed", "2", "--steps", "12", "--json"]).stdout)
    assert again["path"] == runs["random"]["path"]


def test_navigate_refuses_a_scene_without_a_room_and_a_model_of_another_robot(model, pipeline):
    out = fails(["navigate", str(model), "--scene", "traverse"])
    assert "error: scene 'traverse' is not a room to navigate; use room or traverse-room" in out
    out = fails(["navigate", str(pipeline / "model.afford"), "--scene", "room"])
    assert "error: navigation needs a model of the mobile robot's moves (learned from its success readings)" in out
    fails(["navigate", str(model), "--controller", "bold"], code=2)
