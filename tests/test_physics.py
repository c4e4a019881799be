"""Physics gives the thesis's world (issue: what it must show, 3), on pinned layouts.

Every outcome here is whatever PhysX made of the hand's motion; the assertions are about
ground truth read back from the simulator after the fact.
"""

from __future__ import annotations

import numpy as np
import pytest

from afford.sim.objects import ObjectSpec
from tests.conftest import act, label

PUSHES = ("push-forward", "push-left", "push-right")


@pytest.mark.parametrize("push", PUSHES)
@pytest.mark.parametrize("diameter", [0.10, 0.16, 0.25])
def test_a_pushed_sphere_rolls_off_or_out_of_view(table, push, diameter):
    step = act(table, [ObjectSpec("sphere", (diameter,), (0.62, 0.0))], push)
    assert label(step) in ("fell", "left-view")
    assert step.after[0, 0] == 0.0  # the robot no longer sees it
    # The effect keeps the last seen position: only visibility changed.
    assert np.allclose(step.after[0, 1:], step.before[0, 1:])


@pytest.mark.parametrize("push", PUSHES)
@pytest.mark.parametrize("spec", [
    ObjectSpec("box", (0.12, 0.15, 0.12), (0.62, 0.0), 20.0),
    ObjectSpec("box", (0.30, 0.25, 0.20), (0.65, 0.05), 0.0),
    ObjectSpec("cylinder", (0.12, 0.20), (0.62, -0.05)),
])
def test_a_pushed_box_or_upright_cylinder_is_dragged_and_stays(table, push, spec):
    step = act(table, [spec], push)
    assert label(step) == "dragged"
    assert step.after[0, 0] == 1.0
    moved = step.truth_after[0].position - step.truth_before[0].position
    direction = {"push-forward": np.array([1, 0]), "push-left": np.array([0, 1]), "push-right": np.array([0, -1])}[push]
    assert float(moved[:2] @ direction) > 0.03  # it went the way it was pushed
    assert abs(moved[2]) < 0.01  # and did not tip over the edge or rise


def test_a_lying_cylinder_rolls_across_its_axis_and_slides_along_it(table):
    along_x = ObjectSpec("lying-cylinder", (0.10, 0.25), (0.65, 0.0), yaw=0.0)
    rolled = act(table, [along_x], "push-left")      # across the axis
    slid = act(table, [along_x], "push-forward")      # along the axis
    assert label(rolled) in ("fell", "left-view")
    assert label(slid) == "dragged"
    moved = slid.truth_after[0].position - slid.truth_before[0].position
    assert 0.05 < moved[0] < 0.3 and abs(moved[1]) < 0.03
    # Turned by 90 degrees the same object does the opposite.
    along_y = ObjectSpec("lying-cylinder", (0.10, 0.25), (0.65, 0.0), yaw=90.0)
    assert label(act(table, [along_y], "push-forward")) in ("fell", "left-view")
    assert label(act(table, [along_y], "push-left")) == "dragged"


@pytest.mark.parametrize("spec", [
    ObjectSpec("box", (0.12, 0.10, 0.15), (0.65, 0.10), 30.0),
    ObjectSpec("cylinder", (0.12, 0.20), (0.60, -0.10)),
    ObjectSpec("sphere", (0.14,), (0.65, 0.0)),
])
def test_lift_lifts_what_fits_the_hand(table, spec):
    step = act(table, [spec], "lift")
    assert label(step) == "lifted"
    assert step.truth_after[0].in_hand
    assert step.after[0, 0] == 1.0
    z = table.schema.index("z_min")
    assert step.after[0, z] - step.before[0, z] > 0.15  # the robot sees it rise


@pytest.mark.parametrize("spec", [
    ObjectSpec("box", (0.35, 0.35, 0.20), (0.70, 0.0)),
    ObjectSpec("cylinder", (0.32, 0.30), (0.70, 0.0)),
])
def test_lift_fails_on_objects_too_large_for_the_hand(table, spec):
    step = act(table, [spec], "lift")
    assert label(step) != "lifted"
    assert not step.truth_after[0].in_hand
    assert step.truth_after[0].bottom < table.config.world.table_top + 0.02


@pytest.mark.parametrize("name", ["push-forward", "push-left", "push-right", "lift"])
def test_an_object_out_of_reach_does_not_move(table, name):
    far = ObjectSpec("box", (0.10, 0.10, 0.10), (1.02, 0.40))
    step = act(table, [far], name)
    assert not step.executed
    assert not step.contact
    assert label(step) == "no-change"
    assert np.allclose(step.truth_after[0].position, step.truth_before[0].position, atol=1e-3)


@pytest.mark.parametrize("push", PUSHES)
def test_a_pushed_lifted_object_is_dropped(table, push):
    held = ObjectSpec("box", (0.10, 0.10, 0.10), (0.62, 0.0), held=True)
    step = act(table, [held], push)
    before, after = step.truth_before[0], step.truth_after[0]
    assert before.in_hand and before.bottom > table.config.world.table_top + 0.05
    assert not after.in_hand
    assert after.bottom < before.bottom - 0.1  # it came down
    if step.after[0, 0] == 1.0:
        z = table.schema.index("z_max")
        assert step.after[0, z] < step.before[0, z] - 0.1  # the robot sees the drop
