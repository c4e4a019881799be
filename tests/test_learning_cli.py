"""The learning commands end to end on a small exploration, and their refusals."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from afford.app import app
from afford.artifacts import artifact_bytes, read_artifact, write_artifact
from afford.datasets import interactions_from_artifact, interactions_members

runner = CliRunner()


def ok(args):
    result = runner.invoke(app, args)
    assert result.exit_code == 0, (args, result.output)
    return result


def test_each_artefact_names_its_parent(pipeline):
    chain = ["train", "effects", "features", "model"]
    arts = {name: read_artifact(str(pipeline / f"{name}.afford")) for name in chain}
    for parent, child in zip(chain, chain[1:]):
        assert arts[child].manifest["parents"] == [{"kind": arts[parent].kind, "sha256": arts[parent].sha256}]
    assert [arts[n].kind for n in chain] == ["interactions", "effects", "features", "model"]


def test_effect_categories_mean_something(pipeline):
    info = json.loads(ok(["inspect", str(pipeline / "effects.afford"), "--json"]).stdout)
    for name in ("push-forward", "push-left", "push-right"):
        cats = info["behaviors"][name]["categories"]
        assert all({"id", "count", "prototype", "outcomes"} <= set(c) for c in cats)
        assert len(cats[0]["prototype"]) == 43
        mostly = {max(c["outcomes"], key=c["outcomes"].get) for c in cats if max(c["outcomes"].values()) >= 0.8}
        assert "no-change" in mostly and "dragged" in mostly and mostly & {"fell", "left-view"}
        # the vanishing category is a visibility drop, the others keep the object in view
        gone = [c for c in cats if c["outcomes"].get("fell", 0) + c["outcomes"].get("left-view", 0) >= 0.8]
        assert all(c["prototype"]["visibility"] < -0.9 for c in gone)
    lift = info["behaviors"]["lift"]["categories"]
    lifted = [c for c in lift if c["outcomes"].get("lifted", 0) >= 0.8]
    assert lifted and all(c["prototype"]["z_min"] > 0.1 for c in lifted)


def test_model_reports_features_and_predicts(pipeline):
    info = json.loads(ok(["inspect", str(pipeline / "model.afford"), "--json"]).stdout)
    assert len(info["features"]) == 43 and info["kind"] == "model"
    assert set(info["behaviors"]) == {"push-forward", "push-left", "push-right", "lift"}
    assert all(len(b["selected"]) == 12 for b in info["behaviors"].values())
    import re

    gammas = re.findall(r"gamma=([0-9.e+-]+)", ok(["inspect", str(pipeline / "model.afford")]).stdout)
    assert gammas and all(len(g.split("e")[0].replace(".", "").lstrip("0")) <= 4 for g in gammas), gammas  # four digits, not 17
    from afford.learning import forward_model, load_model

    loaded = load_model(str(pipeline / "model.afford"))
    fm = forward_model(loaded)
    assert any(bm.known is not None for bm in fm.behaviors)
    for name, bm in zip(loaded.names, fm.behaviors):
        if bm.known is not None:  # P(known) reads every feature, the category predictor its 12
            assert np.array_equal(bm.known_selected, np.arange(43)) and bm.known.n_features_in_ == 43
            assert bm.predictor.n_features_in_ == 12
    result = json.loads(ok(["evaluate", str(pipeline / "model.afford"), str(pipeline / "test.afford"),
                            "--baselines", "--json"]).stdout)
    for name, m in result["behaviors"].items():
        assert {"accuracy", "n_test", "n_categories", "log_loss", "brier", "ece", "baselines"} <= set(m)
        assert set(m["baselines"]) == {"majority", "knn", "random_forest"}
        assert m["accuracy"] > m["baselines"]["majority"]  # it learned something
        cm = np.array(m["confusion_matrix"])
        assert cm.sum() == m["n_test"]
        # open-set: every interaction scored, a discarded kind one more outcome
        assert m["n_all"] == m["n_test"] + m["n_unknown_effects"] and 0.0 <= m["accuracy_all"] <= 1.0
        right_on_kept = m["accuracy"] * m["n_test"]
        assert m["accuracy_all"] * m["n_all"] <= right_on_kept + m["n_unknown_effects"] + 1e-6


def test_predict_with_check_runs_the_simulator(pipeline):
    out = json.loads(ok(["predict", str(pipeline / "model.afford"), "--seed", "2", "--objects", "2", "--check", "--json"]).stdout)
    assert len(out["objects"]) == 2
    for obj in out["objects"]:
        for name, p in obj["behaviors"].items():
            assert abs(sum(p["probabilities"].values()) + p["unknown"] - 1) < 1e-3
            assert "held" in p and "outcome" in p
    assert out["checked"] == 8 and 0 <= out["held"] <= 8


def test_predict_from_a_layout(pipeline, tmp_path):
    layout = tmp_path / "ball.toml"
    layout.write_text('[[object]]\nshape = "sphere"\nsize = [0.12]\nposition = [0.6, 0.0]\n')
    out = json.loads(ok(["predict", str(pipeline / "model.afford"), "--layout", str(layout), "--json"]).stdout)
    assert out["layout"][0]["shape"] == "sphere"
    bad = tmp_path / "bad.toml"
    bad.write_text('[[object]]\nshape = "cone"\nsize = [0.12]\nposition = [0.6, 0.0]\n')
    result = runner.invoke(app, ["predict", str(pipeline / "model.afford"), "--layout", str(bad)])
    assert result.exit_code == 1


def test_a_pipe_runs_cluster_select_train(pipeline, tmp_path):
    env = dict(os.environ)
    cmd = f"{sys.executable} -m afford"
    # the model goes to this test's own directory, not into the session's shared pipeline
    proc = subprocess.run(
        f"{cmd} cluster {pipeline / 'train.afford'} -o - | {cmd} select-features - -o - --top 8 | "
        f"{cmd} train - -o {tmp_path / 'piped.afford'} --kernel linear",
        shell=True, capture_output=True, env=env)
    assert proc.returncode == 0, proc.stderr.decode()[-2000:]
    assert read_artifact(str(tmp_path / "piped.afford"), "model").manifest["training"]["kernel"] == "linear"


def _variant(pipeline, tmp_path, name, change):
    art = read_artifact(str(pipeline / "train.afford"))
    data = change(interactions_from_artifact(art))
    arrays, meta = interactions_members(data) if name != "nan" else _unchecked(data)
    path = tmp_path / f"{name}.afford"
    write_artifact(str(path), artifact_bytes("interactions", arrays, meta))
    return path


def _unchecked(data):
    from afford.datasets import behaviour_counts

    arrays = {k: getattr(data, k) for k in ("entities", "before_index", "after_index", "behavior", "params", "episode", "step")}
    arrays.update({"truth_" + k: v for k, v in data.truth.items()})
    return arrays, {"schema": data.schema.to_json(), "behaviors": data.behaviors, "scene": data.scene,
                    "shapes": data.shapes, "n_interactions": len(data), "counts": behaviour_counts(data)}


def _err(args):
    result = runner.invoke(app, args)
    assert result.exit_code == 1, result.output
    return result.output


def test_clear_errors(pipeline, tmp_path):
    no_lift = _variant(pipeline, tmp_path, "nolift", lambda d: d.subset(np.flatnonzero(d.behavior != 3)))
    assert "no interactions of behaviour 'lift'" in _err(["cluster", str(no_lift), "-o", str(tmp_path / "x")])
    # held-out data without one behaviour score the others and say which was left out
    scored = json.loads(ok(["evaluate", str(pipeline / "model.afford"), str(no_lift), "--json"]).stdout)
    assert set(scored["behaviors"]) == {"push-forward", "push-left", "push-right"}
    assert scored["not_scored"] == {"lift": "the data hold no interactions of it"}

    def nan(d):
        d.entities[d.before_index[3], 5] = np.nan
        return d
    assert "NaN" in _err(["cluster", str(_variant(pipeline, tmp_path, "nan", nan)), "-o", str(tmp_path / "x")])

    few = _variant(pipeline, tmp_path, "few", lambda d: d.subset(np.arange(60)))
    assert "needs at least" in _err(["cluster", str(few), "-o", str(tmp_path / "x")])

    def one_category(d):
        d.after_index = d.before_index.copy()  # nothing ever happened
        return d
    flat = _variant(pipeline, tmp_path, "flat", one_category)
    ok(["cluster", str(flat), "-o", str(tmp_path / "flat-effects.afford")])
    assert "one effect category only" in _err(["train", str(tmp_path / "flat-effects.afford"), "-o", str(tmp_path / "x")])

    from afford.features import FeatureSchema

    def other_schema(d):
        names = tuple(n if n != "z_max" else "height" for n in d.schema.names)
        d.schema = FeatureSchema(names, d.schema.channels)
        return d
    other = _variant(pipeline, tmp_path, "other", other_schema)
    assert "another feature schema" in _err(["evaluate", str(pipeline / "model.afford"), str(other)])
    assert "needs 'interactions'" in _err(["evaluate", str(pipeline / "model.afford"), str(pipeline / "effects.afford")])
    assert "run 'afford cluster' on it first" in _err(["train", str(pipeline / "train.afford"), "-o", str(tmp_path / "x")])
    assert "--top 1000 is more than the 43 features" in _err(["select-features", str(pipeline / "effects.afford"),
                                                               "-o", str(tmp_path / "x"), "--top", "1000"])
    assert not (tmp_path / "x").exists()


def test_plan_and_execute_in_simulation(pipeline):
    out = json.loads(ok(["plan", str(pipeline / "model.afford"), "--seed", "3", "--reachable",
                         "--goal", "*:visibility=0", "--execute", "--json"]).stdout)
    assert out["goal"] == ["*:visibility=0~0.5"]
    assert out["plan"]["found"]
    assert 0 < out["plan"]["success_probability"] <= 1
    # monitoring and replanning only add to the chance of the plan run blind (100 imagined
    # rollouts: a standard error of at most 0.05)
    assert out["plan"]["success_probability"] >= out["plan"]["open_loop_probability"] - 0.15
    assert out["plan"]["replans_assumed"] == 3
    assert all({"behavior", "object", "alpha", "probability"} <= set(s) for s in out["plan"]["steps"])
    assert isinstance(out["reached"], bool) and out["replans"] >= 0
    if out["reached"]:  # then the object really is gone
        assert out["execution"]["executed"]


def test_plan_execute_shows_each_step_on_stderr_and_keeps_stdout_json(pipeline):
    result = ok(["plan", str(pipeline / "model.afford"), "--seed", "3", "--reachable", "--goal", "*:visibility=0",
                 "--execute", "--json"])
    out = json.loads(result.stdout)
    lines = result.stderr.splitlines()
    assert lines[0].startswith("searching for a plan (3 candidates")
    executed = out["execution"]["executed"]
    starts = [ln for ln in lines if ln.startswith("executing step ")]
    assert len(starts) == len(executed) >= 1
    assert starts[0].endswith(f"{executed[0]['behavior']} on object {executed[0]['object']}")
    assert sum(ln.startswith("replanning") for ln in lines) == out["replans"] + out["execution"]["windfalls"]
    assert (lines[-1] == "goal reached") == out["reached"]


def test_plan_ranks_alternatives_by_success_probability(pipeline):
    args = ["plan", str(pipeline / "model.afford"), "--seed", "3", "--reachable", "--goal", "*:visibility=0", "--json"]
    one = json.loads(ok(args + ["--alternatives", "1"]).stdout)
    out = json.loads(ok(args).stdout)  # three candidates by default
    ranked = [out["plan"]] + out["alternatives"]
    assert 2 <= len(ranked) <= 3 and "alternatives" not in one
    chances = [p["success_probability"] for p in ranked]
    assert chances == sorted(chances, reverse=True)
    assert len({tuple((s["behavior"], s["object"]) for s in p["steps"]) for p in ranked}) == len(ranked)
    # the most probable path is one of the candidates, and none is less likely to work than it
    path = [s["behavior"] for s in one["plan"]["steps"]]
    assert path in [[s["behavior"] for s in p["steps"]] for p in ranked]
    assert out["plan"]["success_probability"] >= one["plan"]["success_probability"]


def test_plan_episodes_report_rates(pipeline):
    out = json.loads(ok(["plan", str(pipeline / "model.afford"), "--seed", "10", "--episodes", "4", "--reachable",
                         "--goal", "*:visibility=0", "--execute", "--json"]).stdout)
    assert out["episodes"] == 4
    assert out["found"] == sum(v["found"] for v in out["by_length"].values())
    assert out["reached"] == sum(v["reached"] for v in out["by_length"].values())
    assert 0 <= out["mean_success_probability"] <= 1
    assert 0 <= out["mean_open_loop_probability"] <= 1
    assert out["first_plan_worked"] <= out["reached"]


def test_plan_refuses_bad_goals(pipeline):
    assert "unknown feature 'colour'" in _err(["plan", str(pipeline / "model.afford"), "--seed", "1", "--goal", "0:colour=1"])
    assert "robot sees" in _err(["plan", str(pipeline / "model.afford"), "--seed", "1", "--goal", "5:visibility=0"])


def test_emulate_an_empty_table(pipeline):
    from pathlib import Path

    layouts = Path(__file__).resolve().parents[1] / "examples" / "layouts"
    out = json.loads(ok(["emulate", str(pipeline / "model.afford"), "--observe", str(layouts / "empty-table.toml"),
                         "--start", str(layouts / "lift-start-1.toml"), "--max-replans", "0", "--json"]).stdout)
    assert out["goal"] == ["0:visibility=0~0.5"]  # the observed table is empty: the object must go
    assert out["found"] and 0 < out["success_probability"] <= 1
    # with no replan the robot runs the plan until it is done or first surprised, and stops there
    executed, planned = out["execution"]["executed"], out["plan"]
    assert out["replans"] == 0 and 1 <= len(executed) <= len(planned)
    assert [s["behavior"] for s in executed] == [s["behavior"] for s in planned[: len(executed)]]
    assert all(s["as_predicted"] for s in executed[:-1])
    assert out["reached"] or not executed[-1]["as_predicted"]


def test_predict_answers_inverse_queries(pipeline):
    out = json.loads(ok(["predict", str(pipeline / "model.afford"), "--seed", "4", "--objects", "2",
                         "--want", "*:visibility=0", "--json"]).stdout)
    probs = [r["probability"] for r in out["ranking"]]
    assert len(probs) == 8 and probs == sorted(probs, reverse=True)
    assert all(0 <= p <= 1 for p in probs)


def test_a_scene_the_model_cannot_perceive_is_refused_once_not_skipped(pipeline):
    result = runner.invoke(app, ["plan", str(pipeline / "model.afford"), "--scene", "traverse-gaps", "--seed", "1",
                                 "--episodes", "2", "--goal", "*:visibility=0"])
    assert result.exit_code == 1 and "perceives 3900 features, the model reads 43" in result.output


def test_cluster_forms_categories_by_the_channels_asked_and_refuses_unknown_ones(pipeline, tmp_path):
    from tests.clitools import fails

    out = json.loads(ok(["cluster", str(pipeline / "train.afford"), "-o", str(tmp_path / "e.afford"),
                         "--channels", "visibility", "--json"]).stdout)
    lift = out["behaviors"]["lift"]["categories"]
    assert len(lift) == 2, "in view or vanished: nothing else tells effects apart"
    assert sorted(round(c["prototype"]["visibility"]) for c in lift) == [-1, 0]
    assert any(abs(c["prototype"]["z_min"]) > 0.01 for c in lift), "prototypes still span every channel"
    msg = fails(["cluster", str(pipeline / "train.afford"), "-o", str(tmp_path / "x.afford"), "--channels", "visibility,colour"])
    assert msg.strip().splitlines() == [f"error: no effect channel 'colour' in {pipeline / 'train.afford'}; "
                                        "its channels are visibility, position, shape"]
    assert not (tmp_path / "x.afford").exists()


def test_the_grasp_scene_clusters_by_visibility_contact_point_and_touch_and_cuts_by_log_loss_unless_told(grasp_learned, tmp_path):
    i, e, e2 = (str(grasp_learned / "train.afford"), str(grasp_learned / "effects.afford"), str(tmp_path / "e2.afford"))
    ok(["cluster", i, "-o", e2, "--channels", "visibility,border", "--kmax", "3"])
    own, told = (read_artifact(p).manifest["effects"]["power-grasp"] for p in (e, e2))
    assert (own["channels"], own["k_max"]) == (["visibility", "cp", "touch"], 4)
    assert (told["channels"], told["k_max"]) == (["visibility", "border"], 3)
    # and it cuts ReliefF's ranking by log loss unless told
    f, f2 = str(grasp_learned / "features.afford"), str(tmp_path / "f2.afford")
    ok(["select-features", e, "-o", f2, "--score", "accuracy"])
    own, told = (read_artifact(p).manifest["relevance"]["power-grasp"] for p in (f, f2))
    assert (own["score"], told["score"]) == ("log_loss", "accuracy")


def test_predict_on_a_grasp_model_runs_each_behaviour_with_the_alpha_it_chose_in_the_grasp_scene(grasp_learned):
    from tests.clitools import fails

    model = str(grasp_learned / "model.afford")
    # no --scene: the model's own scene (grasp), not the table
    out = json.loads(ok(["predict", model, "--seed", "5", "--check", "--json"]).stdout)
    behaviours = out["objects"][0]["behaviors"]
    assert out["checked"] == len(behaviours) == 5
    for name, p in behaviours.items():
        assert "observed_category" in p and "outcome" in p, name
        # every one of the 24 measurements is named in the next state, not none of them
        assert len(p["next"]["features"]) == 24 and "cp_x" in p["next"]["features"], name
    with_alpha = [p for p in behaviours.values() if "alpha" in p]
    assert len(with_alpha) == 5 and all(len(p["alpha"]) == 1 for p in with_alpha)
    human = ok(["predict", model, "--seed", "5"]).stdout
    assert "object 0: cp_x" in human and "scene 0" not in human
    assert f"{with_alpha[2]['alpha'][0]:.2f}" in human  # the alpha each behaviour would use is shown
    # another kind of scene is refused in one sentence naming both and the way out
    msg = fails(["predict", model, "--scene", "traverse", "--seed", "1"])
    assert msg.strip().splitlines() == ["error: scene 'traverse' perceives 3900 features, the model reads 25 "
                                        "(it was learned in scene 'grasp'); leave out --scene to act in the model's own scene"]


def test_a_behaviour_that_never_changed_anything_trains_as_certain_beside_the_others(pipeline, tmp_path):
    """push-forward's effects erased: select-features keeps it one feature, train makes it certain."""
    def still(d):
        pf = d.behavior == d.behavior_names.index("push-forward")
        d.after_index[pf] = d.before_index[pf]
        return d
    path = _variant(pipeline, tmp_path, "still", still)
    e, f, m = (str(tmp_path / n) for n in ("e.afford", "f.afford", "m.afford"))
    ok(["cluster", str(path), "-o", e])
    ok(["select-features", e, "-o", f])
    out = json.loads(ok(["train", f, "-o", m, "--json"]).stdout)
    assert out["behaviors"]["push-forward"]["n_categories"] == 1
    assert out["behaviors"]["lift"]["n_categories"] > 1
    pred = json.loads(ok(["predict", m, "--seed", "3", "--json"]).stdout)
    assert all(o["behaviors"]["push-forward"]["probability"] == 1.0 for o in pred["objects"] if o["visible"])


def test_train_can_choose_c_and_gamma_on_a_sample_and_records_it(pipeline, tmp_path):
    out = tmp_path / "m.afford"
    ok(["train", str(pipeline / "features.afford"), "-o", str(out), "--search-rows", "60"])
    art = read_artifact(str(out))
    assert art.manifest["training"]["search_rows"] == 60
    cv = art.manifest["cv"]
    rows = {n: sum(r["class_counts"].values()) for n, r in cv.items()}
    assert all(rows[n] > 60 for n in cv)  # each behaviour has more rows than the sample
    assert all(r["search_rows"] <= 60 + 2 * len(r["class_counts"]) for r in cv.values())


def test_select_features_records_search_rows_only_where_it_samples_and_refuses_it_where_moot(pipeline, tmp_path):
    e = str(pipeline / "effects.afford")
    f = tmp_path / "f.afford"
    ok(["select-features", e, "-o", str(f), "--search-rows", "60"])
    assert all(r["search_rows"] == 60 for r in read_artifact(str(f)).manifest["relevance"].values())
    top = tmp_path / "top.afford"
    ok(["select-features", e, "-o", str(top), "--top", "5"])
    assert all("search_rows" not in r for r in read_artifact(str(top)).manifest["relevance"].values())
    for extra in (["--top", "5"], ["--method", "forward"]):
        result = runner.invoke(app, ["select-features", e, "-o", str(tmp_path / "no.afford"), "--search-rows", "60", *extra])
        assert result.exit_code == 1 and "makes no such cut" in result.output, result.output
        assert not (tmp_path / "no.afford").exists()


def test_search_rows_takes_any_whole_number_and_refuses_the_rest_in_one_sentence():
    from afford.errors import AffordError
    from afford.learning import search_rows_setting

    assert search_rows_setting(None, None, np.int64(500)) == 500  # numpy's integers from the Python API too
    for bad in (True, 2.5, 5):
        with pytest.raises(AffordError, match="not a whole number of at least 10"):
            search_rows_setting(None, None, bad)
