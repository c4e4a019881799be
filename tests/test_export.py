"""afford export and afford.to_frame: interactions as a table pandas reads back."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest
from typer.testing import CliRunner

import afford
from afford.app import app
from afford.artifacts import read_artifact
from afford.datasets import interactions_from_artifact
from afford.features import FeatureSchema, Interactions

runner = CliRunner()


def test_a_csv_export_reads_into_pandas_with_the_documented_columns(pipeline, tmp_path):
    out = tmp_path / "effects.csv"
    result = runner.invoke(app, ["export", str(pipeline / "effects.afford"), "-o", str(out)])
    assert result.exit_code == 0, result.output
    frame = pd.read_csv(out)
    art = read_artifact(str(pipeline / "effects.afford"))
    data = interactions_from_artifact(art)
    names = list(data.schema.names)
    assert list(frame.columns[:3]) == ["episode", "step", "behavior"]
    assert list(frame.columns[3:3 + len(names)]) == names  # the features, by name, in schema order
    assert len(frame) == len(data) == 480
    assert np.allclose(frame[names].to_numpy(), data.before, atol=1e-6)
    after = [f"after.{n}" for n in names]  # what the robot perceived after, right behind
    assert list(frame.columns[3 + len(names):3 + 2 * len(names)]) == after
    assert np.allclose(frame[after].to_numpy() - frame[names].to_numpy(), data.effects_of(np.arange(len(data))), atol=1e-5, equal_nan=True)
    assert frame["behavior"].tolist() == [data.behavior_names[b] for b in data.behavior]
    assert np.array_equal(frame["category"].to_numpy(), art.arrays["category"])
    outcomes = np.asarray(art.manifest["outcome_labels"])[data.truth["outcome"]]
    assert frame["truth.outcome"].tolist() == outcomes.tolist()  # ground truth by name, apart
    assert [c for c in frame.columns if c.startswith("truth.pose_before.")] == [f"truth.pose_before.{i}" for i in range(7)]


def test_parquet_holds_the_same_table(pipeline, tmp_path):
    runner.invoke(app, ["export", str(pipeline / "effects.afford"), "-o", str(tmp_path / "e.csv")])
    result = runner.invoke(app, ["export", str(pipeline / "effects.afford"), "-o", str(tmp_path / "e.pq"),
                                 "--format", "parquet"])
    assert result.exit_code == 0, result.output
    pq = pd.read_parquet(tmp_path / "e.pq")
    csv = pd.read_csv(tmp_path / "e.csv")
    assert list(pq.columns) == list(csv.columns)
    assert np.allclose(pq["x_min"].to_numpy(), csv["x_min"].to_numpy())
    assert pq["behavior"].tolist() == csv["behavior"].tolist()


def test_given_results_export_by_name(tmp_path):
    path = tmp_path / "t.afford"
    assert runner.invoke(app, ["explore", "--scene", "traverse", "--interactions", "14", "--seed", "3",
                               "-o", str(path)]).exit_code == 0
    frame = afford.to_frame(str(path))
    data = afford.load_interactions(str(path))
    assert frame.shape[0] == 14 and "category" not in frame
    assert frame["result"].tolist() == [data.result_names[r] for r in data.result]
    assert len([c for c in frame.columns if c in set(data.schema.names)]) == 3900


def test_parameters_get_a_column_each_empty_where_a_behaviour_has_none():
    schema = FeatureSchema(names=("visibility", "x"), channels=("visibility", "position"))
    behaviors = [{"name": "grasp", "parameters": [{"name": "angle", "low": 0, "high": 90}]},
                 {"name": "poke", "parameters": []}]
    data = Interactions.from_rows(schema, behaviors, np.array([[1.0, 0.2], [1.0, 0.3], [1.0, 0.4]]), None,
                                  behavior=np.array([0, 1, 0]), params=np.array([[30.0], [0.0], [60.0]]),
                                  episode=np.array([0, 0, 1]), step=np.array([0, 1, 0]),
                                  result=np.array([1, 0, 1]), result_names=["fail", "success"])
    frame = afford.to_frame(data)
    assert frame["alpha.angle"].tolist()[0::2] == [30.0, 60.0] and np.isnan(frame["alpha.angle"][1])
    assert frame["result"].tolist() == ["success", "fail", "success"]


@pytest.mark.parametrize("module, extra", [("pyarrow", "parquet"), ("pandas", "export")])
def test_a_missing_extra_is_named_in_one_sentence(pipeline, tmp_path, monkeypatch, module, extra):
    out = tmp_path / "e.parquet"
    out.write_bytes(b"keep me")
    monkeypatch.setitem(sys.modules, module, None)  # `import module` now fails, as if not installed
    result = runner.invoke(app, ["export", str(pipeline / "effects.afford"), "-o", str(out)])
    assert result.exit_code == 1
    assert f"pip install 'afford[{extra}]'" in result.output and len(result.output.strip().splitlines()) == 1
    assert out.read_bytes() == b"keep me"  # nothing half-written


def test_an_unsupported_format_or_a_model_is_refused(pipeline, tmp_path):
    result = runner.invoke(app, ["export", str(pipeline / "train.afford"), "-o", str(tmp_path / "x"), "--format", "xlsx"])
    assert result.exit_code == 1 and "cannot export to 'xlsx'; the formats are csv and parquet" in result.output
    result = runner.invoke(app, ["export", str(pipeline / "model.afford"), "-o", str(tmp_path / "m.csv")])
    assert result.exit_code == 1 and "of kind 'model'" in result.output
    assert not (tmp_path / "x").exists() and not (tmp_path / "m.csv").exists()
