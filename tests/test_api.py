"""The Python API: the README's example runs as written, and the API is the CLI's own code."""

from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

import afford
from afford.app import app
from afford.artifacts import read_artifact
from afford.features import Interactions

ROOT = Path(__file__).resolve().parents[1]
runner = CliRunner()


def _readme_example() -> str:
    text = (ROOT / "README.md").read_text()
    match = re.search(r"<!-- api-example -->\n```python\n(.*?)```", text, re.S)
    assert match, "README.md lost its <!-- api-example --> block"
    return match.group(1)


def test_the_readme_example_runs_as_written(pipeline, tmp_path):
    for name in ("train.afford", "effects.afford", "model.afford"):
        shutil.copy(pipeline / name, tmp_path / name)
    script = tmp_path / "example.py"
    script.write_text(_readme_example())
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                          env={**os.environ, "PYTHONWARNINGS": "ignore"})
    assert proc.returncode == 0, proc.stderr[-2000:]
    lines = proc.stdout.splitlines()
    assert lines[0].startswith("480 interactions, 43 features")
    assert re.match(r"(reached|not reached) after \d+ replans", lines[-1])
    # what the example saved is an interactions file the CLI reads, of the seed it was given
    info = json.loads(runner.invoke(app, ["inspect", str(tmp_path / "more.afford"), "--json"]).stdout)
    assert info["kind"] == "interactions" and info["seed"] == 7


def test_load_returns_what_each_file_holds(pipeline):
    data = afford.load(str(pipeline / "train.afford"))
    assert isinstance(data, Interactions) and isinstance(afford.load(str(pipeline / "effects.afford")), Interactions)
    assert len(data) == 480 and data.before.shape == (480, len(data.schema.names))
    model = afford.load(str(pipeline / "model.afford"))
    assert isinstance(model, afford.Model) and model.names == data.behavior_names
    labels = afford.load_labels(str(pipeline / "effects.afford"))
    assert np.array_equal(labels, read_artifact(str(pipeline / "effects.afford")).arrays["category"])
    with pytest.raises(afford.AffordError, match="holds no labels"):
        afford.load_labels(str(pipeline / "train.afford"))  # discovered labels need `cluster` first


def test_predict_proba_is_what_afford_predict_reports(pipeline):
    model = afford.load_model(str(pipeline / "model.afford"))
    world = afford.world("table", seed=2, objects=2)
    state = world.perceive()
    out = json.loads(runner.invoke(app, ["predict", str(pipeline / "model.afford"), "--seed", "2", "--objects", "2",
                                         "--json"]).stdout)
    for entry in out["objects"]:
        for name, p in entry["behaviors"].items():
            classes, proba = model.predict_proba(name, state[entry["object"]])
            assert {str(c): round(float(q), 4) for c, q in zip(classes, proba[0])} == p["probabilities"]
            assert int(model.predict(name, state[entry["object"]])[0]) == p["category"]
            # the next state predict shows is the planner's: its forward model's step
            fm = model.forward(min_probability=0.0)
            i, b = entry["object"], fm.index(name)
            nxt = fm.apply(state, i, b, p["category"])[i]
            assert p["next"]["visible"] == bool(model.schema.visible(nxt))
            assert p["next"]["features"] == {model.schema.names[j]: round(float(nxt[j]), 4) for j in model.schema.geometry}


def test_predict_effects_option_chooses_the_members_or_the_prototype(pipeline):
    """--effects prototype moves an object by its category's mean; members (the default)
    by the mean of the nearest members' own effects, with their spread beside it."""
    model = afford.load_model(str(pipeline / "model.afford"))
    state = afford.world("table", seed=2, objects=2).perceive()
    geometry = model.schema.geometry
    moved = 0
    for effects in ("members", "prototype"):
        out = json.loads(runner.invoke(app, ["predict", str(pipeline / "model.afford"), "--seed", "2", "--objects", "2",
                                             "--effects", effects, "--json"]).stdout)
        for entry in out["objects"]:
            i = entry["object"]
            for name, p in entry["behaviors"].items():
                if not p["next"]["visible"]:
                    continue
                members = model.members[name]
                c = p["category"]
                if effects == "prototype":
                    effect = model.prototypes[name][c]
                else:
                    effect = np.zeros(len(model.schema))
                    spread = np.zeros(len(model.schema))
                    for channel in model.schema.channel_names:
                        cols = model.schema.channel_indices(channel)
                        near = members.E_[members.neighbours(state[i], c, channel)][:, cols].astype(float)
                        effect[cols], spread[cols] = near.mean(axis=0), near.std(axis=0)
                    assert p["next"]["spread"] == pytest.approx(
                        {model.schema.names[j]: round(float(spread[j]), 4) for j in geometry}, abs=2e-4)
                want = state[i] + effect
                for j in geometry:
                    assert p["next"]["features"][model.schema.names[j]] == pytest.approx(want[j], abs=2e-4)
                moved += effects == "members" and bool(np.abs(effect - model.prototypes[name][c])[geometry].max() > 0.005)
    assert moved  # somewhere the members predict another move than the prototype


def test_an_unknown_effect_model_is_refused_before_any_work(pipeline):
    r = runner.invoke(app, ["plan", str(pipeline / "model.afford"), "--seed", "1", "--goal", "0:visibility=0",
                            "--effects", "average"])
    assert r.exit_code == 2 and "'average' is not one of 'members', 'prototype'" in " ".join(
        r.output.replace("│", " ").split()), r.output


def test_evaluate_scores_where_both_forward_models_put_things(pipeline):
    out = json.loads(runner.invoke(app, ["evaluate", str(pipeline / "model.afford"), str(pipeline / "test.afford"),
                                         "--json"]).stdout)
    errors = [m["effect_error"]["position"] for m in out["behaviors"].values()]
    assert all(e["n"] > 0 for e in errors)
    # within-category precision: over the behaviours, the members err less at the median
    assert sum(e["members"]["median_cm"] for e in errors) < sum(e["prototype"]["median_cm"] for e in errors)


def test_a_feature_vector_of_the_wrong_length_is_one_sentence(pipeline):
    model = afford.load_model(str(pipeline / "model.afford"))
    with pytest.raises(afford.AffordError, match="give feature vectors of 43 features"):
        model.predict_proba("push-forward", np.zeros((2, 40)))
    with pytest.raises(afford.features.errors.DataError, match="unknown behaviour 'jump'"):
        model.predict_proba("jump", np.zeros((1, 43)))
    with pytest.raises(afford.AffordError, match="finite"):
        model.predict_proba("lift", np.full((1, 43), np.nan))


def test_api_exploration_is_the_cli_exploration(tmp_path):
    runner.invoke(app, ["explore", "--episodes", "3", "--seed", "11", "-o", str(tmp_path / "cli.afford")])
    afford.save(afford.explore("table", episodes=3, seed=11, workers=2), str(tmp_path / "api.afford"), seed=11)
    cli, api = (read_artifact(str(tmp_path / f"{n}.afford")) for n in ("cli", "api"))
    assert cli.manifest["members"] == api.manifest["members"]  # every array, byte for byte


def test_the_plan_the_api_makes_is_the_plan_the_cli_makes(pipeline):
    model = afford.load_model(str(pipeline / "model.afford"))
    plan = model.plan(afford.world("table", seed=4, objects=1).perceive(), "*:visibility=0")
    out = json.loads(runner.invoke(app, ["plan", str(pipeline / "model.afford"), "--seed", "4", "--objects", "1",
                                         "--goal", "*:visibility=0", "--json"]).stdout)
    assert plan.to_json()["steps"] == out["plan"]["steps"]
    assert round(plan.success_probability, 4) == out["plan"]["success_probability"]


def test_a_plan_run_blind_is_judged_by_the_plan_module_and_a_bad_goal_is_one_sentence(pipeline):
    from afford.plan.monitor import blind_probability

    model = afford.load_model(str(pipeline / "model.afford"))
    state = afford.world("table", seed=4, objects=1).perceive()
    plan = model.plan(state, "*:visibility=0")
    assert plan.found and plan.steps
    p = model.blind_probability(state, "*:visibility=0", plan, rollouts=50, seed=2)
    assert 0.0 <= p <= 1.0
    assert p == blind_probability(model.forward(), state, afford.parse_goal("*:visibility=0", model.schema), plan,
                                  rollouts=50, seed=2)
    assert model.blind_probability(state, "0:visibility=1", plan) == 1.0  # the goal holds before any step
    with pytest.raises(afford.AffordError, match="unknown feature 'no_such'"):
        model.blind_probability(state, "0:no_such=1", plan)


def test_plan_blind_rollouts_reports_the_apis_blind_probability_and_its_mean_over_scenes(pipeline):
    model_path = str(pipeline / "model.afford")
    args = ["plan", model_path, "--seed", "4", "--objects", "1", "--goal", "*:visibility=0", "--json"]
    out = json.loads(runner.invoke(app, args + ["--blind-rollouts", "50"]).stdout)
    assert "blind_probability" not in json.loads(runner.invoke(app, args).stdout)["plan"]  # off unless asked
    model = afford.load_model(model_path)
    state = afford.world("table", seed=4, objects=1).perceive()
    plan = model.plan(state, "*:visibility=0")
    assert out["plan"]["blind_probability"] == round(model.blind_probability(state, "*:visibility=0", plan,
                                                                             rollouts=50, seed=4), 4)
    assert out["blind_probability"] == out["plan"]["blind_probability"] and out["plan"]["blind_rollouts"] == 50
    many = json.loads(runner.invoke(app, ["plan", model_path, "--seed", "4", "--objects", "1", "--episodes", "3",
                                          "--goal", "*:visibility=0", "--blind-rollouts", "20", "--json"]).stdout)
    values = [r["plan"]["blind_probability"] for r in many["runs"] if r["plan"]["found"]]
    assert values and many["mean_blind_probability"] == pytest.approx(np.mean(values), abs=1e-4)
    bad = runner.invoke(app, args + ["--blind-rollouts", "-1"])
    assert bad.exit_code == 2


def test_version_and_light_import():
    proc = subprocess.run([sys.executable, "-m", "afford", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and proc.stdout.strip() == f"afford {afford.__version__}"
    assert re.fullmatch(r"\d+\.\d+\.\d+.*", afford.__version__)
    code = "import sys, afford.features; sys.exit(int('sapien' in sys.modules or 'afford.api' in sys.modules))"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


def test_the_learning_chain_from_python_is_the_cli_chain(pipeline, tmp_path):
    """afford.cluster | select_features | train write the members the commands write."""
    progress = []
    afford.cluster(str(pipeline / "train.afford"), str(tmp_path / "e.afford"), seed=1,
                   progress=lambda done, total: progress.append((done, total)))
    assert progress[-1] == (4, 4)
    afford.select_features(str(tmp_path / "e.afford"), str(tmp_path / "f.afford"), top=12)
    summary = afford.train(str(tmp_path / "f.afford"), str(tmp_path / "m.afford"))
    assert set(summary["behaviors"]) == {"push-forward", "push-left", "push-right", "lift"}
    for mine, theirs in (("e", "effects"), ("f", "features"), ("m", "model")):
        ours = read_artifact(str(tmp_path / f"{mine}.afford")).manifest["members"]
        assert ours == read_artifact(str(pipeline / f"{theirs}.afford")).manifest["members"], theirs
