"""The mobile robot through the one command line: explore, inspect, learn with given labels, predict, refuse."""

from __future__ import annotations

import json

import numpy as np
import pytest

from tests.clitools import fails, ok

TRAVERSE = ("traverse", "traverse-body", "traverse-gaps", "traverse-ramps")


@pytest.fixture(scope="module")
def learned(traverse_learned):
    return traverse_learned


def test_the_traverse_scenes_are_listed_with_their_moves():
    out = json.loads(ok(["scenes", "--json"]).stdout)
    scenes = {s["name"]: s for s in out["scenes"]}
    for name in TRAVERSE:
        moves = scenes[name]["behaviors"]
        assert len(moves) == 7 and all(m["target"] is None and m["parameters"] == [] for m in moves)
        assert {m["name"] for m in moves} >= {"go-forward", "turn-left-60", "turn-right-20"}


def test_exploration_records_given_results_on_3900_grid_features(learned):
    info = json.loads(ok(["inspect", str(learned / "train.afford"), "--json"]).stdout)
    assert len(info["features"]) == 3900 and info["label_source"] == "given"
    assert {c["channel"]: c["n"] for c in info["channels"]} == {"range": 300, "shape": 3600}
    assert info["visibility"] is None and info["histograms"] == 200
    assert info["n_interactions"] == 36 * 7
    rates = [r["success"] for r in info["result_rates"].values()]
    assert len(rates) == 7 and 0.0 < min(rates) and max(rates) < 1.0  # neither all success nor all failure


def test_an_environment_is_stored_once_for_its_seven_moves(learned):
    from afford.artifacts import read_artifact

    art = read_artifact(str(learned / "train.afford"))
    assert art.arrays["entities"].shape == (36, 3900) and art.arrays["entities"].dtype == np.float32
    assert "after_index" not in art.arrays and art.arrays["result"].shape == (36 * 7,)


def test_learning_with_given_results_needs_no_cluster_step(learned):
    info = json.loads(ok(["inspect", str(learned / "model.afford"), "--json"]).stdout)
    assert info["label_source"] == "given"
    assert set(info["n_selected"]) == set(info["behavior_names"]) and max(info["n_selected"].values()) <= 3900
    for p in info["predictors"].values():  # the thesis's 5-fold cross-validation, per behaviour
        assert p["cv"]["n_splits"] == 5 and 0.5 <= p["cv"]["cv_accuracy"] <= 1.0
        assert set(p["results"]) == {"fail", "success"} and sum(p["results"].values()) == 36
    out = json.loads(ok(["evaluate", str(learned / "model.afford"), str(learned / "test.afford"), "--baselines",
                         "--json"]).stdout)
    for name, m in out["behaviors"].items():
        assert m["n_test"] == 8 and 0.0 <= m["accuracy"] <= 1.0
        assert m["n_all"] == 8 and m["accuracy_all"] == m["accuracy"]  # given results: nothing is discarded
        assert {"majority", "random_forest"} <= set(m["baselines"])


def test_predict_check_runs_every_move_from_the_same_start(learned):
    out = json.loads(ok(["predict", str(learned / "model.afford"), "--scene", "traverse", "--seed", "4", "--check",
                         "--json"]).stdout)
    assert len(out["objects"]) == 1 and out["checked"] == 7 and out["label_source"] == "given"
    for p in out["objects"][0]["behaviors"].values():
        assert p["result"] in ("fail", "success") and p["observed_result"] in ("fail", "success")
        assert abs(sum(p["probabilities"].values()) - 1) < 1e-3


def test_predict_plot_draws_the_scan_and_each_moves_chance(learned, tmp_path):
    from matplotlib.image import imread

    out = json.loads(ok(["predict", str(learned / "model.afford"), "--scene", "traverse", "--seed", "4", "--check",
                         "--plot", str(tmp_path / "scan.png"), "--json"]).stdout)
    assert out["plot"] == str(tmp_path / "scan.png")
    image = imread(tmp_path / "scan.png")
    assert image.shape[1] >= 800 and image.shape[0] >= 300  # the scan beside seven bars


def test_commands_refuse_what_does_not_apply_in_one_sentence(learned, pipeline, tmp_path):
    model = str(learned / "model.afford")
    assert "does not apply to scene 'traverse'" in fails(["explore", "--scene", "traverse", "--size-min", "0.1",
                                                           "-o", str(tmp_path / "x")], code=2)
    assert "--objects does not apply" in fails(["predict", model, "--scene", "traverse", "--seed", "1", "--objects", "2"],
                                               code=2)
    assert "nothing after its behaviours" in fails(["cluster", str(learned / "train.afford"), "-o", str(tmp_path / "x")])
    assert "labels were given" in fails(["plan", model, "--scene", "traverse", "--seed", "1", "--goal", "*:l0_r0_c0_min=1"])
    table = tmp_path / "table.toml"
    table.write_text('[[object]]\nshape = "box"\nsize = [0.1, 0.1, 0.1]\nposition = [0.6, 0.0]\nheld = true\n')
    assert "held" in fails(["predict", model, "--scene", "traverse", "--layout", str(table)])
    ramp = tmp_path / "ramp.toml"
    ramp.write_text("[[ramp]]\nposition = [0.6, 0.0]\nyaw = 0.0\nwidth = 1.0\nlength = 1.0\nslope = 10.0\n")
    assert "unknown table 'ramp'" in fails(["predict", str(pipeline / "model.afford"), "--layout", str(ramp)])
    # a layout of the table's frame given to the mobile robot, and the other way round
    shown = (table.read_text().replace("held = true\n", ""), 'scene = "traverse"\n' + ramp.read_text())
    for text, declared, on, user in (("scene = \"table\"\n" + shown[0], "table", "traverse", model),
                                      (shown[1], "traverse", "table", str(pipeline / "model.afford"))):
        (tmp_path / "other.toml").write_text(text)
        assert fails(["predict", user, "--layout", str(tmp_path / "other.toml")]).strip().splitlines() == [
            f"error: {tmp_path / 'other.toml'} is a layout of scene '{declared}'; scene '{on}' reads layouts "
            "in another frame, so it cannot use it"]
    # and a table scene for a model of the mobile robot's moves: one sentence naming both
    assert "(it was learned in scene 'traverse'); leave out --scene" in fails(
        ["predict", model, "--scene", "table", "--seed", "1"])
    assert not (tmp_path / "x").exists()


def test_a_goal_on_a_feature_the_schema_lacks_is_refused(learned):
    from afford.plan.goals import GoalError, parse_goal
    from afford.sim.registry import make_scene

    schema = make_scene("traverse").schema
    with pytest.raises(GoalError, match="unknown feature 'z_min'"):
        parse_goal(["0:z_min=0.9"], schema)
    assert parse_goal(["0:l0_r2_c2_min>1.5"], schema).holds(np.full((1, 3900), 2.0))


EXAMPLES = {"box-ahead": "fail", "ball-ahead": "success", "bar-low": "fail", "bar-high": "success",
            "ramp-gentle": "success", "ramp-steep": "fail", "gap-narrow": "success", "gap-wide": "fail"}


@pytest.mark.parametrize("name", sorted(EXAMPLES))
def test_the_example_layouts_do_what_their_comments_say(name):
    from pathlib import Path

    from afford.scenes_io import open_world, scene_layout

    path = Path(__file__).parents[1] / "examples" / "layouts" / "traverse" / f"{name}.toml"
    scene, layout = scene_layout("traverse", None, str(path))
    world = open_world(scene, layout, 0)
    before = world.perceive()
    after = world.act("go-forward", 0)
    assert np.array_equal(before, after)  # nothing is perceived after a move: the start stays the entity
    assert scene.results[world.last_result] == EXAMPLES[name]


def test_the_grid_is_a_setting_chapter_6_uses_30_by_30_in_one_layer(tmp_path):
    out = json.loads(ok(["explore", "--scene", "traverse-gaps", "--episodes", "1", "--grid", "30", "--layers", "1",
                         "-o", str(tmp_path / "g.afford"), "--json"]).stdout)
    assert out["n_features"] == 30 * 30 * 39 and out["channels"] == {"range": 2700, "shape": 32400}
    assert "--grid does not apply to scene 'table'" in fails(["explore", "--scene", "table", "--grid", "5",
                                                              "-o", str(tmp_path / "x")], code=2)


def test_kernel_and_folds_override_the_scenes_learner(learned, tmp_path):
    default = json.loads(ok(["inspect", str(learned / "model.afford"), "--json"]).stdout)["training"]
    assert (default["kernel"], default["folds"]) == ("linear", 5)  # the thesis's chapter 5 learner
    ok(["select-features", str(learned / "train.afford"), "--kernel", "rbf", "-o", str(tmp_path / "f.afford")])
    ok(["train", str(tmp_path / "f.afford"), "--kernel", "rbf", "--folds", "3", "-o", str(tmp_path / "m.afford")])
    info = json.loads(ok(["inspect", str(tmp_path / "m.afford"), "--json"]).stdout)
    assert (info["training"]["kernel"], info["training"]["folds"]) == ("rbf", 3)
    assert all(p["cv"]["n_splits"] == 3 and "gamma" in p["cv"]["best_params"] for p in info["predictors"].values())
    assert "--folds" in fails(["train", str(tmp_path / "f.afford"), "--folds", "1", "-o", str(tmp_path / "x")], code=2)


def test_a_forest_learns_from_every_grid_feature(learned, tmp_path):
    # no select-features: a forest reads all 3900 features
    model = str(tmp_path / "m.afford")
    out = ok(["train", str(learned / "train.afford"), "--kernel", "forest", "--folds", "2", "--seed", "2", "-o", model])
    assert "random forest" in out.stdout and "smallest leaf" in out.stdout and "3900" in out.stdout
    info = json.loads(ok(["inspect", model, "--json"]).stdout)
    assert info["training"]["kernel"] == "forest"
    assert all("min_samples_leaf" in p["cv"]["best_params"] for p in info["predictors"].values())
    check = json.loads(ok(["predict", model, "--scene", "traverse", "--seed", "4", "--check", "--json"]).stdout)
    assert check["checked"] == 7
    for p in check["objects"][0]["behaviors"].values():
        assert p["result"] in ("fail", "success") and abs(sum(p["probabilities"].values()) - 1) < 1e-3
