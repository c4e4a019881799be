"""Curiosity-driven exploration from the command line (thesis chapter 6, issue 12): the robot
scans candidate environments and acts only where its learner is unsure."""

from __future__ import annotations

import json
import zipfile
import io

import numpy as np
import pytest
from typer.testing import CliRunner

from afford.app import app

runner = CliRunner()


def ok(args):
    r = runner.invoke(app, args)
    assert r.exit_code == 0, (args, r.output)
    return r


def explore_curiously(d, scene: str, test_episodes: int, *curious: str) -> tuple[dict, np.ndarray]:
    """A test set of ``scene``, then a curious exploration with it: the ``--json`` report and
    which candidates x behaviours were tried (the artefact's ``online_tried``)."""
    ok(["explore", "--scene", scene, "--episodes", str(test_episodes), "--seed", "50", "--workers", "2",
        "-o", str(d / "test.afford")])
    out = json.loads(ok(["explore", "--scene", scene, *curious, "--workers", "2", "--test", str(d / "test.afford"),
                         "-o", str(d / "cur.afford"), "--json"]).stdout)
    with zipfile.ZipFile(d / "cur.afford") as z:
        return out, np.load(io.BytesIO(z.read("online_tried.npy")), allow_pickle=False)


@pytest.fixture(scope="module")
def curious(tmp_path_factory):
    d = tmp_path_factory.mktemp("curious")
    return d, *explore_curiously(d, "traverse-gaps", 12, "--strategy", "margin", "--candidates", "70", "--bootstrap", "35",
                                 "--seed", "3", "--plots", str(d / "figs"))


def test_it_tries_the_bootstrap_and_then_only_what_interests_it(curious):
    d, out, tried = curious
    import afford

    data = afford.load_interactions(str(d / "cur.afford"))
    assert tried.shape == (70, 7) and tried[:35].all()
    for b, name in enumerate(data.behavior_names):
        rows = np.flatnonzero(data.behavior == b)
        assert sorted(data.episode[rows].tolist()) == np.flatnonzero(tried[:, b]).tolist()
        assert out["behaviors"][name]["tried"] + out["behaviors"][name]["skipped"] == 70
    assert len(data) == int(tried.sum()) == out["interactions"] < 70 * 7  # some candidates were skipped
    curve = out["curve"]
    assert {c["behavior"] for c in curve} == set(data.behavior_names)
    assert all(0 <= c["accuracy"] <= 1 and 35 <= c["interactions"] <= 70 for c in curve)
    assert out["plots"] == [str(d / "figs" / "learning-curve.png")]
    online = json.loads(ok(["inspect", str(d / "cur.afford"), "--json"]).stdout)["online"]
    assert online["strategy"] == "margin" and online["bootstrap"] == 35 and online["candidates"] == 70
    assert {n: b["tried"] for n, b in online["behaviors"].items()} == {n: b["tried"] for n, b in out["behaviors"].items()}


def test_train_takes_what_curiosity_explored(curious, tmp_path):
    d, _, _ = curious
    r = ok(["train", str(d / "cur.afford"), "-o", str(tmp_path / "m.afford"), "--json"])
    assert set(json.loads(r.stdout)["behaviors"]) == {"go-forward", "turn-left-20", "turn-right-20", "turn-left-40",
                                                       "turn-right-40", "turn-left-60", "turn-right-60"}


def test_a_candidate_is_the_environment_algorithm_1_would_explore_and_workers_do_not_matter(tmp_path):
    import afford
    from afford.sim.explore import scan_candidates

    scene = afford.make_scene("traverse-body")
    explored = afford.explore(scene, episodes=3, seed=8)
    assert np.array_equal(scan_candidates(scene, 3, seed=8), explored.entities)
    args = ["explore", "--scene", "traverse-body", "--strategy", "committee", "--candidates", "14", "--bootstrap", "8",
            "--seed", "4"]
    ok([*args, "-o", str(tmp_path / "one.afford")])
    ok([*args, "--workers", "2", "-o", str(tmp_path / "two.afford")])
    members = lambda p: {n: zipfile.ZipFile(p).read(n) for n in zipfile.ZipFile(p).namelist() if n.endswith(".npy")}
    assert members(tmp_path / "one.afford") == members(tmp_path / "two.afford")


def test_curiosity_options_are_checked(tmp_path):
    out = str(tmp_path / "x.afford")
    r = runner.invoke(app, ["explore", "--scene", "grasp", "--strategy", "entropy", "--candidates", "10", "-o", out])
    assert r.exit_code == 1 and "behaviours with parameters is not built" in r.output
    r = runner.invoke(app, ["explore", "--strategy", "entropy", "--candidates", "30", "--bootstrap", "5", "-o", out])
    assert r.exit_code == 1 and "--bootstrap must be between 10 and the 30 candidates" in r.output
    r = runner.invoke(app, ["explore", "--strategy", "entropy", "--max-steps", "3", "-o", out])
    assert r.exit_code == 2 and "--max-steps does not go with --strategy" in " ".join(r.output.replace("│", " ").split())
    r = runner.invoke(app, ["explore", "--tau", "0.2", "-o", out])
    assert r.exit_code == 2 and "--tau goes with --strategy" in " ".join(r.output.replace("│", " ").split())
    r = runner.invoke(app, ["explore", "--scene", "traverse", "--strategy", "margin", "--episodes", "5", "-o", out])
    assert r.exit_code == 2 and "--episodes does not go with --strategy" in " ".join(r.output.replace("│", " ").split())
    assert not list(tmp_path.iterdir())


@pytest.fixture(scope="module")
def curious_table(tmp_path_factory):
    d = tmp_path_factory.mktemp("curious-table")
    return d, *explore_curiously(d, "table", 20, "--strategy", "entropy", "--candidates", "80", "--bootstrap", "30",
                                 "--seed", "5")


def test_at_the_table_it_is_curious_about_the_effect_categories_it_discovered(curious_table, tmp_path):
    import afford
    from afford.sim.explore import scan_candidate

    d, out, tried = curious_table
    data = afford.load_interactions(str(d / "cur.afford"))
    scene = afford.make_scene("table")
    assert tried.shape == (80, 4) and out["with_object"] <= 80
    assert len(data) == int(tried.sum()) < 80 * 4  # the bootstrap, then only what interested it
    for b, name in enumerate(data.behavior_names):
        rows = np.flatnonzero(data.behavior == b)
        assert sorted(data.episode[rows].tolist()) == np.flatnonzero(tried[:, b]).tolist()
        assert tried[:, b].sum() >= 30 and out["behaviors"][name]["n_categories"] >= 2
    # a row starts from what the candidate looked like, and its effect is what PhysX did:
    # a lift that lifted raised the object's perceived top, a push moved it or left it
    for r in (0, len(data) // 2, len(data) - 1):
        assert np.array_equal(data.before[r], scan_candidate(scene, 5, int(data.episode[r])))
    top = data.effects[:, data.schema.names.index("z_max")]
    lifted = (data.behavior == 3) & (data.truth["outcome"] == data.outcome_names.index("lifted"))
    still = data.truth["outcome"] == data.outcome_names.index("no-change")
    assert lifted.sum() >= 3 and np.median(top[lifted]) > 0.15 and np.median(np.abs(top[still])) < 0.02
    curve = out["curve"]
    assert {c["behavior"] for c in curve} == set(data.behavior_names)
    assert all(0 <= c["accuracy"] <= 1 and c["interactions"] >= 30 for c in curve)
    # the artefact is ordinary interactions: the table's pipeline takes it (written to this
    # test's own directory, not the module fixture's)
    ok(["cluster", str(d / "cur.afford"), "-o", str(tmp_path / "e.afford")])
    ok(["train", str(tmp_path / "e.afford"), "-o", str(tmp_path / "m.afford")])


def test_a_table_test_set_without_first_steps_of_a_behaviour_is_refused(tmp_path):
    ok(["explore", "--episodes", "2", "--seed", "1", "-o", str(tmp_path / "tiny.afford")])
    r = runner.invoke(app, ["explore", "--strategy", "entropy", "--candidates", "14", "--bootstrap", "10",
                            "--test", str(tmp_path / "tiny.afford"), "-o", str(tmp_path / "x.afford")])
    assert r.exit_code == 1 and "have no first step of behaviour" in r.output
    assert not (tmp_path / "x.afford").exists()
