"""``--plots DIR``: the figures of inspect and evaluate, and the reliability bins behind them.

Built from small synthetic inputs in the shapes ``describe()`` and ``evaluate_model()``
produce, so nothing here runs the simulator.
"""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest
from typer.testing import CliRunner

from afford.app import app
from afford.artifacts import artifact_bytes
from afford.datasets import interactions_members
from afford.errors import AffordError
from afford.plots import artefact_plots, evaluation_plots, plot_directory
from afford.features import OUTCOMES, Interactions, object_schema
from afford.learn.evaluate import evaluate_predictions, reliability_bins

runner = CliRunner()
SCHEMA = object_schema()


def is_png(path) -> bool:
    return path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def category(cid: int, count: int, rng, outcomes: dict) -> dict:
    proto = {name: 0.0 for name in SCHEMA.names}
    for name in ("x_min", "x_max", "elevation_03", "azimuth_10"):
        proto[name] = round(float(rng.normal(0, 0.1)), 5)
    if cid == 0:
        proto["visibility"] = -1.0
    return {"id": cid, "count": count, "prototype": proto, "outcomes": outcomes}


@pytest.fixture
def info():
    """What ``describe()`` gives for a features artefact (push-left) and a model (lift: no scores)."""
    rng = np.random.default_rng(0)
    scores = {name: round(float(s), 5) for name, s in zip(SCHEMA.names, rng.random(len(SCHEMA)))}
    ranked = sorted(scores, key=lambda n: -scores[n])
    return {
        "kind": "features",
        "features": SCHEMA.to_json()["features"],
        "histogram_columns": [list(h) for h in SCHEMA.histograms],
        "behaviors": {
            "push-left": {"categories": [category(0, 12, rng, {"fell": 0.9, "left-view": 0.1}),
                                         category(1, 30, rng, {"dragged": 1.0}),
                                         category(2, 8, rng, {"no-change": 0.75, "dragged": 0.25})],
                          "selected": ranked[:5] + [ranked[30]], "relevance": scores},
            "lift": {"categories": [category(0, 4, rng, {"lifted": 1.0}), category(1, 9, rng, {})],
                     "selected": ["z_min", "elevation_04"]},
        },
        "outcomes": {b: {s: {label: int(rng.integers(0, 9)) for label in OUTCOMES} for s in ("box", "sphere")}
                     for b in ("push-left", "lift")},
    }


def test_inspect_figures_have_the_expected_names(tmp_path, info):
    directory = plot_directory(tmp_path / "new" / "plots")  # parents are created
    paths = artefact_plots(info, directory)
    names = {"prototypes-push-left.png", "relevance-push-left.png", "prototypes-lift.png", "relevance-lift.png",
             "outcomes.png"}
    assert sorted(p.rsplit("/", 1)[-1] for p in paths) == sorted(names)
    assert {p.name for p in directory.iterdir()} == names
    assert all(is_png(directory / n) for n in names)


def test_evaluate_figures_have_the_expected_names(tmp_path):
    metrics = {"accuracy": 0.75, "n_test": 8, "n_unknown_effects": 0, "n_categories": 3, "log_loss": 0.6,
               "brier": 0.3, "ece": 0.12, "labels": [0, 1, 2], "confusion_matrix": [[3, 1, 0], [0, 2, 0], [0, 1, 1]],
               "reliability": [{"confidence": 0.45, "accuracy": 0.5, "count": 2},
                               {"confidence": 0.93, "accuracy": 0.8333, "count": 6}]}
    paths = evaluation_plots({"push-forward": metrics}, plot_directory(tmp_path))
    assert [p.rsplit("/", 1)[-1] for p in paths] == ["confusion-push-forward.png", "reliability-push-forward.png"]
    assert all(is_png(tmp_path / p.rsplit("/", 1)[-1]) for p in paths)


def test_a_plot_directory_that_is_a_file_is_refused(tmp_path):
    blocker = tmp_path / "taken"
    blocker.write_text("")
    with pytest.raises(AffordError, match="is a file"):
        plot_directory(blocker)


@pytest.fixture
def interactions_file(tmp_path):
    """A tiny synthetic interactions artefact (no simulator)."""
    rng = np.random.default_rng(1)
    n = 12
    before = rng.random((n, len(SCHEMA)))
    data = Interactions.from_rows(
        schema=SCHEMA,
        behaviors=[{"name": "push-left", "parameters": []}, {"name": "lift", "parameters": []}],
        before=before, after=before + rng.normal(0, 0.01, before.shape),
        behavior=np.arange(n) % 2, params=np.zeros((n, 1)), episode=np.arange(n) // 3, step=np.arange(n) % 3,
        truth={"shape": rng.integers(0, 2, n), "outcome": rng.integers(0, len(OUTCOMES), n)},
        shapes=["box", "sphere"], scene={"name": "synthetic"},
    )
    arrays, meta = interactions_members(data)
    path = tmp_path / "tiny.afford"
    path.write_bytes(artifact_bytes("interactions", arrays, meta, seed=0))
    return path


def test_inspect_plots_an_interactions_file(tmp_path, interactions_file):
    out = tmp_path / "figs"
    result = runner.invoke(app, ["inspect", str(interactions_file), "--json", "--plots", str(out)])
    assert result.exit_code == 0, result.output
    info = json.loads(result.stdout)
    assert info["plots"] == [str(out / "outcomes.png")]
    assert is_png(out / "outcomes.png")
    assert result.stderr.startswith("wrote 1 plot:\n")


def test_plots_into_a_file_exits_1(tmp_path, interactions_file):
    blocker = tmp_path / "taken.png"
    blocker.write_bytes(b"keep")
    for args in (["inspect", str(interactions_file)], ["evaluate", "model.afford", str(interactions_file)]):
        result = runner.invoke(app, [*args, "--plots", str(blocker)])
        assert result.exit_code == 1, result.output
        assert result.stderr.strip().splitlines() == [
            f"error: the plot directory {blocker} is a file; give --plots a directory (it is created if missing)"]
        assert result.stdout == ""
    assert blocker.read_bytes() == b"keep"


def test_reliability_bins_by_hand():
    # confidences .95 (right) .91 (wrong) | .45 (right) .42 (right) | .62 (an unseen category: wrong)
    y = [0, 1, 2, 1, 7]
    proba = [[0.95, 0.03, 0.02], [0.91, 0.05, 0.04], [0.25, 0.30, 0.45], [0.35, 0.42, 0.23], [0.62, 0.30, 0.08]]
    bins = reliability_bins(y, proba, [0, 1, 2])
    assert [b["count"] for b in bins] == [2, 1, 2]
    assert [b["accuracy"] for b in bins] == [1.0, 0.0, 0.5]
    assert [b["confidence"] for b in bins] == pytest.approx([0.435, 0.62, 0.93])
    # the ECE is the count-weighted gap over the same bins
    assert evaluate_predictions(y, proba, [0, 1, 2])["ece"] == pytest.approx(0.4 * 0.565 + 0.2 * 0.62 + 0.4 * 0.43)
    two = reliability_bins(y, proba, [0, 1, 2], n_bins=2)
    assert [(b["count"], b["accuracy"]) for b in two] == [(2, 1.0), (3, pytest.approx(1 / 3))]
    assert two[1]["confidence"] == pytest.approx((0.95 + 0.91 + 0.62) / 3)
    assert reliability_bins([0], [[1.0, 0.0]], [0, 1]) == [{"confidence": 1.0, "accuracy": 1.0, "count": 1}]
    with pytest.raises(ValueError, match="n_bins"):
        reliability_bins(y, proba, [0, 1, 2], n_bins=0)
    with pytest.raises(ValueError, match="one row per label"):
        reliability_bins([0, 1], proba, [0, 1, 2])


def test_commands_that_do_not_plot_do_not_import_matplotlib():
    code = "import sys, afford.app; sys.exit('matplotlib' in sys.modules)"
    assert subprocess.run([sys.executable, "-c", code]).returncode == 0


# -- what the robot saw and did: --plot FILE.png on predict, plan and emulate ----------------

def _png_size(path) -> tuple[int, int]:
    from matplotlib.image import imread

    image = imread(path)
    return image.shape[1], image.shape[0]


def test_predict_plan_and_emulate_draw_what_the_robot_saw(pipeline, tmp_path):
    model = str(pipeline / "model.afford")
    layouts = __import__("pathlib").Path(__file__).resolve().parents[1] / "examples" / "layouts"
    runs = {
        "predict.png": ["predict", model, "--seed", "5", "--objects", "2", "--check"],
        "plan.png": ["plan", model, "--seed", "3", "--reachable", "--goal", "*:visibility=0", "--execute"],
        "emulate.png": ["emulate", model, "--observe", str(layouts / "close-shown.toml"),
                        "--start", str(layouts / "close-start-1.toml")],
    }
    for name, args in runs.items():
        result = runner.invoke(app, [*args, "--plot", str(tmp_path / name), "--json"])
        assert result.exit_code == 0, result.output
        assert json.loads(result.stdout)["plot"] == str(tmp_path / name)
        assert is_png(tmp_path / name) and (tmp_path / name).stat().st_size > 20_000
        width, height = _png_size(tmp_path / name)
        assert width >= 800 and height >= 400, (name, width, height)
    # predict draws the range image and one top view per behaviour: two rows of three panels
    assert _png_size(tmp_path / "predict.png")[1] > _png_size(tmp_path / "plan.png")[1]


def test_the_start_view_outlines_each_object_the_robot_tracks(pipeline):
    import afford

    world = afford.world("table", seed=5, objects=3)
    ranges, boxes = world.start_view
    state = world.perceive()
    assert ranges.ndim == 2 and len(boxes) == state.shape[0] == 3
    # box i holds object i: the camera looks across the table along +y, so the nearer an
    # object's centre is to it (the smaller its y), the lower in the image its box lies
    y = world.scene.schema.index("y_min"), world.scene.schema.index("y_max")
    order_by_y = np.argsort([f[y[0]] + f[y[1]] for f in state])
    order_by_row = np.argsort([-(r0 + r1) for r0, _, r1, _ in boxes])
    assert list(order_by_y) == list(order_by_row)


def test_plot_files_are_checked_before_any_work(pipeline, tmp_path):
    model = str(pipeline / "model.afford")
    r = runner.invoke(app, ["predict", model, "--seed", "1", "--plot", str(tmp_path / "p.txt")])
    assert r.exit_code == 1 and "ending in .png" in r.output
    r = runner.invoke(app, ["predict", model, "--seed", "1", "--plot", str(tmp_path / "no" / "p.png")])
    assert r.exit_code == 1 and "does not exist" in r.output
    r = runner.invoke(app, ["plan", model, "--seed", "1", "--episodes", "2", "--goal", "*:visibility=0",
                            "--plot", str(tmp_path / "p.png")])
    assert r.exit_code == 2 and not list(tmp_path.iterdir())


def test_categories_are_named_from_their_prototypes_numbers():
    from afford.reports import category_name

    still = {"visibility": 0.0, "x_min": 0.0, "x_max": 0.0, "y_min": 0.0, "y_max": 0.0, "z_min": 0.0}
    assert category_name({**still, "visibility": -1.0}) == "vanished"
    assert category_name({**still, "z_min": 0.25, "x_min": 0.1, "x_max": 0.1}) == "lifted 25 cm"
    assert category_name({**still, "x_min": 0.11, "x_max": 0.13}) == "+12 cm x"
    assert category_name({**still, "y_min": -0.2, "y_max": -0.16, "x_min": 0.05, "x_max": 0.05}) == "-18 cm y"
    assert category_name({**still, "x_min": 0.01}) == "no change"
    assert category_name({"min_range_0": -0.31, "theta_3": 0.1}) == "min_range_0 -0.31"


def test_evaluate_names_categories_and_inspect_draws_the_first_looks(pipeline, tmp_path):
    r = runner.invoke(app, ["evaluate", str(pipeline / "model.afford"), str(pipeline / "test.afford"), "--json"])
    assert r.exit_code == 0, r.output
    for report in json.loads(r.stdout)["behaviors"].values():
        assert set(report["label_names"]) == {str(c) for c in report["labels"]}
        assert all(isinstance(v, str) and v for v in report["label_names"].values())
    r = runner.invoke(app, ["inspect", str(pipeline / "train.afford"), "--plots", str(tmp_path), "--json"])
    assert r.exit_code == 0, r.output
    info = json.loads(r.stdout)
    assert str(tmp_path / "range-images.png") in info["plots"] and is_png(tmp_path / "range-images.png")
    # the re-simulated first looks are the ones the exploration recorded, feature for feature
    assert len(info["range_images"]) == 6
    assert all(s["matches_recording"] and s["objects"] >= 1 for s in info["range_images"])
