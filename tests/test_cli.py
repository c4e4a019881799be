"""The command line as scripts use it: exit codes, JSON, stdout carrying one thing, pipes."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from afford.app import app

runner = CliRunner()


@pytest.fixture(scope="module")
def interactions(tmp_path_factory):
    path = tmp_path_factory.mktemp("data") / "table.afford"
    result = runner.invoke(app, ["explore", "--episodes", "12", "--seed", "1", "-o", str(path), "--json"])
    assert result.exit_code == 0, result.output
    return path, json.loads(result.stdout)


def test_scenes_lists_the_table_and_its_behaviours():
    result = runner.invoke(app, ["scenes", "--json"])
    assert result.exit_code == 0
    table = next(s for s in json.loads(result.stdout)["scenes"] if s["name"] == "table")
    assert [b["name"] for b in table["behaviors"]] == ["push-forward", "push-left", "push-right", "lift"]


def test_explore_summary(interactions):
    _, summary = interactions
    assert summary["episodes"] == 12
    assert summary["interactions"] == sum(summary["counts"].values()) >= 12
    assert summary["interactions_per_second"] > 0
    assert set(summary["counts"]) == {"push-forward", "push-left", "push-right", "lift"}


def test_inspect_reports_an_interactions_file(interactions):
    path, summary = interactions
    result = runner.invoke(app, ["inspect", str(path), "--json"])
    assert result.exit_code == 0
    info = json.loads(result.stdout)
    assert info["kind"] == "interactions"
    assert info["schema_version"] == 3
    assert len(info["sha256"]) == 64 and info["parents"] == []
    assert len(info["features"]) == 43
    assert {f["channel"] for f in info["features"]} == {"visibility", "position", "shape"}
    assert info["counts"] == summary["counts"]
    total = sum(c for shapes in info["outcomes"].values() for labels in shapes.values() for c in labels.values())
    assert total == summary["interactions"]
    assert set(info["outcomes"]["lift"]) == {"box", "cylinder", "lying-cylinder", "sphere"}
    assert set(info["outcomes"]["lift"]["box"]) == {"fell", "left-view", "lifted", "dragged", "no-change"}


def test_inspect_human_report_shows_the_same_tables(interactions):
    path, _ = interactions
    # a wide terminal, whatever runs the tests (rich shortens column titles to fit 80 columns)
    result = runner.invoke(app, ["inspect", str(path)], env={"COLUMNS": "160"})
    assert result.exit_code == 0
    for text in ("interactions", "features (43)", "visibility", "position", "shape", "push-left", "lying-cylinder", "no-change"):
        assert text in result.stdout


@pytest.mark.parametrize("args, code", [
    (["explore", "--episodes", "0", "-o", "x.afford"], 2),
    (["explore", "--episodes", "1", "--interactions", "1", "-o", "x.afford"], 2),
    (["explore", "--episodes", "1"], 2),
    (["explore", "--scene", "kitchen", "-o", "x.afford"], 1),
    (["explore", "--episodes", "1", "--size-min", "0.3", "--size-max", "0.1", "-o", "x.afford"], 2),
    (["explore", "--episodes", "1", "--size-min", "0", "-o", "x.afford"], 2),
    (["explore", "--episodes", "1", "-o", ""], 1),
    (["inspect", "does-not-exist.afford"], 1),
])
def test_bad_input_exit_codes(tmp_path, monkeypatch, args, code):
    monkeypatch.chdir(tmp_path)
    result = runner.invoke(app, args)
    assert result.exit_code == code
    assert not (tmp_path / "x.afford").exists()


def _run(*args, stdin=None):
    env = dict(os.environ)
    env.pop("AFFORD_DEBUG", None)
    return subprocess.run([sys.executable, "-m", "afford", *args], input=stdin, capture_output=True, env=env)


def test_errors_are_one_sentence_without_traceback(tmp_path):
    bogus = tmp_path / "bogus.afford"
    bogus.write_text("not a zip")
    proc = _run("inspect", str(bogus))
    assert proc.returncode == 1
    lines = proc.stderr.decode().strip().splitlines()
    assert lines == [f"error: {bogus} is not an afford file"]
    proc = _run("explore", "--scene", "kitchen", "-o", str(tmp_path / "x.afford"))
    assert proc.returncode == 1
    assert proc.stderr.decode().strip().splitlines() == ["error: unknown scene 'kitchen'; known scenes: crane-lift, grasp, room, table, traverse, traverse-body, traverse-furniture, traverse-gaps, traverse-one, traverse-ramps, traverse-room"]


def test_debug_shows_the_traceback(tmp_path):
    bogus = tmp_path / "bogus.afford"
    bogus.write_text("not a zip")
    env = dict(os.environ, AFFORD_DEBUG="1")
    proc = subprocess.run([sys.executable, "-m", "afford", "inspect", str(bogus)], capture_output=True, env=env)
    assert proc.returncode != 0 and b"Traceback" in proc.stderr


def test_explore_pipes_into_inspect():
    explore = _run("explore", "--episodes", "3", "--seed", "2", "-o", "-")
    assert explore.returncode == 0
    assert explore.stdout[:2] == b"PK"  # stdout carries the artefact and nothing else
    assert b"explored" in explore.stderr  # the report went to stderr
    inspect = _run("inspect", "-", "--json", stdin=explore.stdout)
    assert inspect.returncode == 0, inspect.stderr
    assert json.loads(inspect.stdout)["kind"] == "interactions"


def test_an_existing_file_survives_a_failed_run(tmp_path, interactions):
    path, _ = interactions
    target = tmp_path / "keep.afford"
    target.write_bytes(path.read_bytes())
    result = runner.invoke(app, ["explore", "--scene", "kitchen", "-o", str(target)])
    assert result.exit_code == 1
    assert target.read_bytes() == path.read_bytes()


@pytest.mark.parametrize("text, message", [
    ("object = [1, 2]", "must be an [[object]] table"),
    ('[[object]]\nshape = "box"\nsize = "big"\nposition = [0.6, 0.0]\n', "object 0: size must be a list of numbers"),
    ('[[object]]\nshape = "box"\nsize = [0.1, 0.1, 0.1]\nposition = [0.6, 0.0]\nyaw = nan\n', "must be finite"),
    ('[[object]]\nshape = "cone"\nsize = [0.1]\nposition = [0.6, 0.0]\n', "unknown shape 'cone'"),
])
def test_bad_layouts_are_one_sentence(tmp_path, text, message):
    from afford.sim.layout import LayoutError, load_layout

    path = tmp_path / "bad.toml"
    path.write_text(text)
    with pytest.raises(LayoutError) as info:
        load_layout(path)
    assert message in str(info.value)
    assert str(info.value).count(str(path)) == 1
