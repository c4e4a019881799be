"""Beyond one laptop (issue 15): the same bytes on loky, on Dask and after a resume; runs that
survive SIGINT, SIGTERM and kill -9; shards merged into the one-shot run. Every cluster here
binds 127.0.0.1 only and is torn down."""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
from typer.testing import CliRunner

from afford.app import app

AFFORD = [sys.executable, "-m", "afford"]
EPISODES = ["--episodes", "60", "--seed", "5"]


def run(args, cwd, **kw):
    return subprocess.run([*AFFORD, *args], cwd=cwd, capture_output=True, text=True, **kw)


def arrays(path: Path) -> dict[str, str]:
    """The .npy members' checksums: what must be the same bytes."""
    with zipfile.ZipFile(path) as z:
        return {n: hashlib.sha256(z.read(n)).hexdigest() for n in z.namelist() if n.endswith(".npy")}


@pytest.fixture(scope="module")
def one_shot(tmp_path_factory):
    """The reference: 60 table episodes of seed 5, on one worker, uninterrupted."""
    d = tmp_path_factory.mktemp("oneshot")
    r = run(["explore", *EPISODES, "-o", "one.afford"], d)
    assert r.returncode == 0, r.stderr
    assert not (d / "one.afford.partial").exists()  # the journal goes once the output is whole
    return d / "one.afford"


def _records(journal: Path) -> int:
    from afford.journal import Journal

    return Journal(journal, {}).count()


def _start_and_wait(tmp_path: Path, out: str, episodes: int, at_least: int):
    """Start an exploration and wait until its journal holds ``at_least`` episodes."""
    # a shell that starts its jobs in the background (`make test &`) leaves SIGINT ignored,
    # which the child would inherit, and Python then never raises KeyboardInterrupt: the
    # child gets SIGINT's default back, as from a terminal
    proc = subprocess.Popen([*AFFORD, "explore", "--episodes", str(episodes), "--seed", "5", "-o", out],
                            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 90
    journal = tmp_path / (out + ".partial")
    while time.time() < deadline:
        if journal.is_dir() and _records(journal) >= at_least:
            return proc, journal
        if proc.poll() is not None:
            pytest.fail(f"explore ended before its journal held {at_least} episodes: {proc.stderr.read()}")
        time.sleep(0.05)
    proc.kill()
    pytest.fail("the journal did not grow")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_an_interrupted_run_keeps_its_episodes_and_resumes_to_the_same_bytes(one_shot, tmp_path, sig):
    proc, journal = _start_and_wait(tmp_path, "r.afford", 60, at_least=8)
    os.kill(proc.pid, sig)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130 and "Traceback" not in err, err
    kept = _records(journal)
    assert 8 <= kept < 60
    assert f"{kept} finished episodes are kept in r.afford.partial" in err and "--resume" in err
    assert not (tmp_path / "r.afford").exists()
    # the same command without --resume refuses to start over the kept work
    again = run(["explore", *EPISODES, "-o", "r.afford"], tmp_path)
    assert again.returncode == 1 and "give --resume" in again.stderr and _records(journal) == kept
    done = run(["explore", *EPISODES, "-o", "r.afford", "--resume", "--workers", "2"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert arrays(tmp_path / "r.afford") == arrays(one_shot)
    assert not journal.exists()


def test_kill_9_leaves_the_journal_readable_up_to_the_last_whole_episode(one_shot, tmp_path):
    proc, journal = _start_and_wait(tmp_path, "k.afford", 60, at_least=5)
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    kept = _records(journal)
    assert kept >= 5
    log = journal / "episodes.log"
    whole = log.read_bytes()
    # a record a killed writer had only begun: a header promising more bytes than follow
    with open(log, "ab") as f:
        f.write(whole[:40])
    assert _records(journal) == kept
    done = run(["explore", *EPISODES, "-o", "k.afford", "--resume"], tmp_path)
    assert done.returncode == 0, done.stderr
    assert arrays(tmp_path / "k.afford") == arrays(one_shot)


def test_a_journal_of_another_run_is_refused_and_kept(tmp_path):
    import afford
    from afford.errors import Interrupted

    def stop_after_3(done, total):
        if done >= 3:
            raise KeyboardInterrupt

    journal = tmp_path / "j.afford.partial"
    with pytest.raises(Interrupted, match="8 finished episodes are kept"):  # a task is 8 episodes
        afford.explore("table", episodes=60, seed=5, journal=journal, progress=stop_after_3)
    before = (journal / "episodes.log").read_bytes()
    runner = CliRunner()
    for args, why in ((["--seed", "6", "--episodes", "60"], "its seed is 5, this run's 6"),
                      (["--seed", "5", "--episodes", "80"], "its episodes is 60, this run's 80"),
                      (["--seed", "5", "--episodes", "60", "--size-max", "0.2"],
                       "its scene settings differ: size_range: [0.08, 0.4] and [0.08, 0.2]")):
        r = runner.invoke(app, ["explore", *args, "-o", str(tmp_path / "j.afford"), "--resume"])
        assert r.exit_code == 1 and why in r.output and r.output.count("\n") == 1, r.output
    assert (journal / "episodes.log").read_bytes() == before
    assert not (tmp_path / "j.afford").exists()


def test_a_journal_that_names_the_learner_defaults_still_resumes(one_shot, tmp_path):
    """Journals written before the identity left the scene's learner defaults out (how to
    cluster and train: not how rows are explored) resume; changing those defaults does not
    change an exploration."""
    import afford
    from afford.errors import Interrupted

    def stop_after_3(done, total):
        if done >= 3:
            raise KeyboardInterrupt

    journal = tmp_path / "o.afford.partial"
    with pytest.raises(Interrupted):
        afford.explore("table", episodes=60, seed=5, journal=journal, progress=stop_after_3)
    identity = json.loads((journal / "identity.json").read_text())
    assert "learner" not in identity["scene"]
    identity["scene"]["learner"] = {"search_rows": 3000}  # as an older afford wrote it
    (journal / "identity.json").write_text(json.dumps(identity))
    r = CliRunner().invoke(app, ["explore", *EPISODES, "-o", str(tmp_path / "o.afford"), "--resume"])
    assert r.exit_code == 0, r.output
    assert arrays(tmp_path / "o.afford") == arrays(one_shot)


def test_shards_merge_into_the_one_shot_run_and_bad_shards_are_refused(one_shot, tmp_path):
    runner = CliRunner()

    def explore(name, *args):
        r = runner.invoke(app, ["explore", "--seed", "5", *args, "-o", str(tmp_path / name)])
        assert r.exit_code == 0, r.output

    explore("a.afford", "--episode-start", "0", "--episode-count", "25")
    explore("b.afford", "--episode-start", "25", "--episode-count", "35", "--workers", "2")
    r = runner.invoke(app, ["merge", str(tmp_path / "b.afford"), str(tmp_path / "a.afford"), "-o", str(tmp_path / "m.afford")])
    assert r.exit_code == 0, r.output
    assert arrays(tmp_path / "m.afford") == arrays(one_shot)
    # a shard whose scene's learner defaults differ (an afford that trains otherwise) explored the same data
    from afford.artifacts import artifact_bytes, read_artifact, write_artifact

    b = read_artifact(str(tmp_path / "b.afford"))
    own = ("format", "kind", "schema_version", "afford_version", "created", "command", "seed", "parents", "members")
    meta = {k: v for k, v in b.manifest.items() if k not in own}
    meta["scene"] = {**meta["scene"], "learner": {"search_rows": 3000}}
    write_artifact(str(tmp_path / "b2.afford"), artifact_bytes("interactions", dict(b.arrays), meta, seed=b.manifest["seed"],
                                                               parents=b.manifest["parents"], blobs=dict(b.blobs)))
    r = runner.invoke(app, ["merge", str(tmp_path / "a.afford"), str(tmp_path / "b2.afford"), "-o", str(tmp_path / "m3.afford")])
    assert r.exit_code == 0, r.output
    # merged shards are a shard themselves: the merged file merges on
    explore("c.afford", "--episode-start", "60", "--episode-count", "5")
    r = runner.invoke(app, ["merge", str(tmp_path / "m.afford"), str(tmp_path / "c.afford"), "-o", str(tmp_path / "m2.afford"), "--json"])
    assert r.exit_code == 0 and '"episodes": [\n  0,\n  65\n ]' in r.output

    explore("over.afford", "--episode-start", "20", "--episode-count", "10")
    explore("gap.afford", "--episode-start", "30", "--episode-count", "10")
    explore("seed.afford", "--episode-start", "25", "--episode-count", "5", "--seed", "6")
    explore("cut.afford", "--interactions", "30")
    explore("small.afford", "--episode-start", "25", "--episode-count", "35", "--size-max", "0.2")
    r = runner.invoke(app, ["explore", "--scene", "traverse-gaps", "--episode-start", "25", "--episode-count", "1",
                            "-o", str(tmp_path / "gaps.afford")])
    assert r.exit_code == 0, r.output
    for shards, message in (
            (["a.afford", "over.afford"], "both hold episodes 20-24"),
            (["a.afford", "gap.afford"], "episodes 25-29 are in none of the shards"),
            (["a.afford", "seed.afford"], "different seeds (5 and 6)"),
            (["a.afford", "cut.afford"], "cut.afford is no shard"),
            (["a.afford", "small.afford"], "different scene settings (size_range: [0.08, 0.4] and [0.08, 0.2])"),
            (["a.afford", "gaps.afford"], "different scenes (table and traverse-gaps)")):
        r = runner.invoke(app, ["merge", *[str(tmp_path / s) for s in shards], "-o", str(tmp_path / "bad.afford")])
        assert r.exit_code == 1 and message in r.output, (shards, r.output)
        assert not (tmp_path / "bad.afford").exists()


def test_shard_and_backend_options_are_checked(tmp_path):
    runner = CliRunner()
    out = str(tmp_path / "x.afford")
    for args, message in ((["--episode-start", "5"], "--episode-count"),
                          (["--episode-count", "5", "--interactions", "40"], "does not go with"),
                          (["--scheduler", "tcp://127.0.0.1:1"], "needs --backend dask")):
        r = runner.invoke(app, ["explore", *args, "-o", out])
        assert r.exit_code == 2 and message in " ".join(r.output.replace("│", " ").split()), r.output
    r = runner.invoke(app, ["explore", "--episodes", "3", "--resume", "-o", "-"])
    assert r.exit_code == 1 and "--resume needs -o FILE" in r.output


def test_without_the_dask_extra_the_backend_says_how_to_get_it(tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed now fails
    r = CliRunner().invoke(app, ["explore", "--episodes", "3", "--backend", "dask", "-o", str(tmp_path / "x.afford")])
    assert r.exit_code == 1 and "pip install 'afford[dask]'" in r.output
    assert not list(tmp_path.iterdir())


def test_a_scheduler_that_does_not_answer_is_one_sentence(tmp_path):
    r = run(["explore", "--episodes", "3", "--backend", "dask", "--scheduler", "tcp://127.0.0.1:1", "-o", "x.afford"],
            tmp_path)
    assert r.returncode == 1 and r.stderr.startswith("error: no Dask scheduler answers at tcp://127.0.0.1:1")
    assert r.stderr.count("\n") == 1 and not list(tmp_path.iterdir())


def test_dask_gives_the_same_bytes_on_its_own_cluster_and_on_a_running_one(one_shot, tmp_path):
    from distributed import Client, LocalCluster

    r = run(["explore", *EPISODES, "--backend", "dask", "--workers", "2", "-o", "own.afford"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert arrays(tmp_path / "own.afford") == arrays(one_shot)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                      dashboard_address="127.0.0.1:0") as cluster, Client(cluster) as client:
        addresses = [cluster.scheduler_address, *client.scheduler_info()["workers"]]
        assert all(a.startswith("tcp://127.0.0.1:") for a in addresses), addresses
        r = run(["explore", *EPISODES, "--backend", "dask", "--scheduler", cluster.scheduler_address,
                 "-o", "theirs.afford"], tmp_path)
        assert r.returncode == 0, r.stderr
        assert len(client.scheduler_info()["workers"]) == 2  # the cluster is still there after
    assert arrays(tmp_path / "theirs.afford") == arrays(one_shot)


def test_traverse_scans_are_the_same_bytes_on_loky_and_on_dask_with_one_worker():
    import afford

    def members(data):
        from afford.datasets import interactions_members

        return {k: v.tobytes() for k, v in interactions_members(data)[0].items()}

    loky = afford.explore("traverse-gaps", episodes=4, seed=2, workers=2)
    dask = afford.explore("traverse-gaps", episodes=4, seed=2, workers=1, backend="dask")
    assert members(loky) == members(dask)
    assert set(loky.episode.tolist()) == {0, 1, 2, 3}


def test_a_run_to_a_number_of_interactions_resumes_to_the_same_rows(tmp_path):
    import afford
    from afford.datasets import interactions_members
    from afford.errors import Interrupted

    def stop_at_60(done, total):
        if done >= 60:
            raise KeyboardInterrupt

    journal = tmp_path / "i.partial"
    with pytest.raises(Interrupted):
        afford.explore("table", interactions=150, seed=8, workers=2, journal=journal, progress=stop_at_60)
    resumed = afford.explore("table", interactions=150, seed=8, journal=journal, resume=True)
    one = afford.explore("table", interactions=150, seed=8)
    assert len(resumed) == 150
    a, b = interactions_members(one)[0], interactions_members(resumed)[0]
    assert a.keys() == b.keys() and all(a[k].tobytes() == b[k].tobytes() for k in a)


def test_two_runs_never_write_one_journal(tmp_path):
    import afford
    from afford.errors import AffordError, Interrupted

    journal = tmp_path / "x.afford.partial"

    def second_run_meanwhile(done, total):
        if done >= 8:
            with pytest.raises(AffordError, match="another afford explore is writing"):
                afford.explore("table", episodes=60, seed=5, journal=journal, resume=True)
            raise KeyboardInterrupt

    with pytest.raises(Interrupted, match="8 finished episodes are kept"):  # the refused run took nothing
        afford.explore("table", episodes=60, seed=5, journal=journal, progress=second_run_meanwhile)


def test_an_interruption_inside_a_records_write_still_keeps_the_whole_ones(tmp_path, monkeypatch):
    """Ctrl-C can land while a record is half written, and the flush that follows can fail:
    the run still ends as an interruption, names what the journal holds whole, and resumes."""
    import afford
    from afford import journal as journal_module
    from afford.datasets import interactions_members
    from afford.errors import Interrupted

    real_append = journal_module.Journal.append
    calls = []

    def append_cut_short(self, pairs):
        calls.append(len(pairs))
        if len(calls) < 2:
            return real_append(self, pairs)
        self._log.write(journal_module._HEAD.pack(journal_module._MAGIC, 99, 1 << 20, 0) + b"half a record")
        raise KeyboardInterrupt

    def fsync_fails(fd):
        raise OSError(5, "Input/output error")

    monkeypatch.setattr(journal_module.Journal, "append", append_cut_short)
    monkeypatch.setattr(journal_module.os, "fsync", fsync_fails)
    journal = tmp_path / "h.partial"
    with pytest.raises(Interrupted, match="8 finished episodes are kept"):
        afford.explore("table", episodes=24, seed=5, journal=journal)
    assert calls == [8, 8]
    monkeypatch.undo()
    assert _records(journal) == 8  # the half record is not one
    resumed = afford.explore("table", episodes=24, seed=5, journal=journal, resume=True)
    one = afford.explore("table", episodes=24, seed=5)
    a, b = interactions_members(one)[0], interactions_members(resumed)[0]
    assert a.keys() == b.keys() and all(a[k].tobytes() == b[k].tobytes() for k in a)
