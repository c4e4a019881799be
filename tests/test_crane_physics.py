"""The chapter-7 crane in SAPIEN: what it lifts, what it cannot, and what the robot sees."""

from __future__ import annotations

import numpy as np
import pytest

from afford.sim.crane import CRANE_OUTCOMES
from afford.sim.explore import interact, run_episode
from afford.sim.registry import make_scene
from afford.sim.traverse import Item, TraverseLayout

SCENE = make_scene("crane-lift")
LIFT = next(b for b in SCENE.behaviors if b.name == "lift")
FORWARD = next(b for b in SCENE.behaviors if b.name == "move-forward")
R_B = SCENE.schema.index("r_b")


def _try(item: Item, behavior=LIFT, seed: int = 0):
    world = SCENE.build(TraverseLayout(items=(item,)), np.random.default_rng(seed))
    before = world.perceive()
    assert before.shape[0] == 1, "the object stands in view"
    step = interact(world, behavior, 0, before=before)
    return world, step


def test_a_flat_topped_box_within_reach_is_lifted_and_seen_high():
    world, step = _try(Item("box", (0.3, 0.3, 0.3), (0.6, 0.0), 20.0))
    assert step.executed
    assert CRANE_OUTCOMES[step.outcomes[0]] == "lifted"
    assert world.truth()[0].bottom > 0.45
    # The thesis's lift goal: the object's bottom row rises above the image's middle (180 of 360).
    assert step.before[0, R_B] < 180 < step.after[0, R_B]


def test_an_upright_cylinder_is_lifted():
    _, step = _try(Item("cylinder", (0.3, 0.3), (0.55, -0.15), 0.0))
    assert CRANE_OUTCOMES[step.outcomes[0]] == "lifted"


@pytest.mark.parametrize("item", [Item("sphere", (0.3,), (0.6, 0.0)), Item("lying-cylinder", (0.3, 0.4), (0.6, 0.0), 30.0)],
                         ids=["sphere", "lying-cylinder"])
def test_the_magnet_finds_no_flat_face_on_a_sphere_or_a_lying_cylinder(item):
    world, step = _try(item)
    assert step.executed, "the crane reached and tried"
    assert CRANE_OUTCOMES[step.outcomes[0]] != "lifted"
    assert world.robot.held is None
    assert world.truth()[0].bottom < 0.02


def test_a_box_90_cm_away_is_beyond_the_crane():
    world, step = _try(Item("box", (0.3, 0.3, 0.3), (0.9, 0.0), 0.0))
    assert not step.executed
    assert CRANE_OUTCOMES[step.outcomes[0]] == "no-change"


def test_after_a_move_the_robot_still_knows_the_object_nearer_by_what_it_drove():
    item = Item("box", (0.3, 0.3, 0.3), (0.95, 0.05), 0.0)
    world, step = _try(item, FORWARD)
    assert step.after[0, 0] == 1.0, "tracked across the move"
    drove = world.odometry.displacement_m
    assert 0.35 < drove < 0.55
    # Where the robot computes the box to be moved back by about what it drove (its view of
    # the box changes as it nears: more of the top shows).
    ahead_before, ahead_after = world.place(step.before[0])[0, 0], world.place(step.after[0])[0, 0]
    assert ahead_before - ahead_after == pytest.approx(drove, abs=0.1)
    # ... and then it is in reach: the move made the lift possible (a two-step plan).
    lift = interact(world, LIFT, 0, before=step.after)
    assert CRANE_OUTCOMES[lift.outcomes[0]] == "lifted"


def test_an_exploration_episode_records_every_behaviour_from_one_scan():
    data = run_episode(SCENE, seed=3, episode=0)
    assert len(data) in (0, len(SCENE.behaviors))
    if len(data):
        assert (data.before_index == 0).all() and sorted(data.after_index.tolist()) == list(range(1, 7))
        assert data.outcome_names == list(CRANE_OUTCOMES)
    again = run_episode(SCENE, seed=3, episode=0)
    assert np.array_equal(data.entities, again.entities)
