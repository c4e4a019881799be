"""The mobile crane through the one command line: explore, cluster with the scene's k-means, plan and execute."""

from __future__ import annotations

import json

import pytest

from tests.clitools import fails, ok

BEHAVIOURS = "move-forward, move-left-30, move-right-30, move-left-60, move-right-60, lift"


@pytest.fixture(scope="module")
def explored(tmp_path_factory):
    d = tmp_path_factory.mktemp("crane")
    ok(["explore", "--scene", "crane-lift", "--episodes", "150", "--seed", "1", "--workers", "2", "-o", str(d / "i.afford")])
    # Every test gets the whole pipeline here, not from another test: xdist may run them apart.
    ok(["cluster", str(d / "i.afford"), "-o", str(d / "e.afford")])
    ok(["train", str(d / "e.afford"), "-o", str(d / "m.afford")])
    return d


def test_the_scene_clusters_with_its_own_k_means_and_lift_splits_lifted_from_not(explored):
    d = explored
    out = json.loads(ok(["cluster", str(d / "i.afford"), "-o", str(d / "e1.afford"), "--json"]).stdout)
    lift = out["behaviors"]["lift"]
    assert lift["n_categories"] == 2
    shares = [c["outcomes"].get("lifted", 0.0) for c in lift["categories"]]
    assert max(shares) > 0.9 and min(shares) < 0.1, "one category is the lifts, the other is not"
    assert out["behaviors"]["move-forward"]["n_categories"] <= 4


def test_k_per_behaviour_and_bad_k_in_one_sentence(explored):
    d = explored
    out = json.loads(ok(["cluster", str(d / "i.afford"), "-o", str(d / "e6.afford"), "--k", "6", "--k", "lift=3",
                         "--min-fraction", "0", "--json"]).stdout)
    assert out["behaviors"]["lift"]["n_categories"] == 3
    assert out["behaviors"]["move-forward"]["n_categories"] == 6
    msg = fails(["cluster", str(d / "i.afford"), "-o", str(d / "x.afford"), "--k", "jump=3"])
    assert msg.strip().splitlines() == [f"error: there is no behaviour 'jump' to give a k; the behaviours are {BEHAVIOURS}"]
    assert not (d / "x.afford").exists()
    fails(["cluster", str(d / "i.afford"), "-o", str(d / "x.afford"), "--k", "lift=two"], code=2)


def test_a_move_then_lift_plan_is_found_and_reaches_its_goal_in_simulation(explored):
    d = explored
    # An upright cylinder beyond the crane, ahead and to the left: it must be approached first.
    (d / "far.toml").write_text('[[object]]\nshape = "cylinder"\nsize = [0.3, 0.3]\nposition = [0.9, 0.2]\n')
    out = json.loads(ok(["plan", str(d / "m.afford"), "--scene", "crane-lift", "--layout", str(d / "far.toml"),
                         "--goal", "*:r_b>180", "--search", "bfs", "--max-depth", "4", "--execute", "--json"]).stdout)
    names = [s["behavior"] for s in out["plan"]["steps"]]
    assert names[-1] == "lift" and len(names) >= 2, names
    assert out["execution"]["reached"]


def test_the_case_studys_button_is_drawn_on_asking_and_only_where_it_applies(explored):
    d = explored
    import afford
    from afford.sim.scenes.crane_lift import BUTTON

    items = afford.world("crane-lift", seed=3, objects=2, button=True).layout.items
    assert len(items) == 3 and items[-1].fixed and items[-1].size == BUTTON["size"]
    assert not any(it.fixed for it in afford.world("crane-lift", seed=3, objects=2).layout.items)
    out = json.loads(ok(["plan", str(d / "m.afford"), "--scene", "crane-lift", "--seed", "3", "--objects", "2", "--button",
                         "--goal", "*:r_b>180", "--json"]).stdout)
    assert 1 <= out["objects"] <= 3
    from afford.sim.scene import SceneOptionError

    with pytest.raises(SceneOptionError, match="--button does not apply to scene 'table'"):
        afford.world("table", seed=1, button=True)


def test_comparison_goals_on_unknown_features_and_bfs_past_its_depth_say_so(explored):
    d = explored
    msg = fails(["plan", str(d / "m.afford"), "--scene", "crane-lift", "--seed", "3", "--goal", "*:height>0.5"])
    assert msg.strip().splitlines()[-1].startswith("error:") and "height" in msg and "Traceback" not in msg
    out = json.loads(ok(["plan", str(d / "m.afford"), "--scene", "crane-lift", "--seed", "3", "--goal", "*:r_b>400",
                         "--search", "bfs", "--max-depth", "2", "--json"]).stdout)
    assert not out["plan"]["found"] and out["plan"]["reason"] == "no plan of at most 2 steps reaches the goal"
    fails(["plan", str(d / "m.afford"), "--scene", "crane-lift", "--seed", "3", "--goal", "*:r_b>400", "--search", "bfs",
           "--max-depth", "9"], code=2)


def test_inspect_lists_only_the_shapes_the_scene_places(explored):
    """The crane draws from the solid shapes the table shares with the hand's mug; its
    ground-truth table must not list a mug it never placed."""
    info = json.loads(ok(["inspect", str(explored / "i.afford"), "--json"]).stdout)
    assert set(info["outcomes"]["lift"]) == {"box", "cylinder", "lying-cylinder", "sphere"}
    assert sum(c for labels in info["outcomes"]["lift"].values() for c in labels.values()) == info["counts"]["lift"]
