"""Files from strangers and outputs anywhere (the hostile-input battery): forged artefacts,
odd output paths, signals; and the same bytes for every artefact."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

AFFORD = [sys.executable, "-m", "afford"]


def run(args, cwd, env=None, **kw):
    return subprocess.run([*AFFORD, *args], cwd=cwd, capture_output=True,
                          env={**os.environ, "SOURCE_DATE_EPOCH": "1700000000", **(env or {})}, **kw)


def test_the_learning_chain_writes_the_same_bytes_twice(pipeline, tmp_path):
    """Same seed, same input, same command: byte-identical effects, features and model files
    (skops's object ids and timestamps are canonicalised; SOURCE_DATE_EPOCH fixes `created`)."""
    outs = []
    for name in ("a", "b"):
        d = tmp_path / name
        d.mkdir()
        shutil.copy(pipeline / "test.afford", d / "train.afford")  # 160 rows: quick
        for args in (["cluster", "train.afford", "-o", "effects.afford", "--seed", "1"],
                     ["select-features", "effects.afford", "-o", "features.afford", "--top", "8"],
                     ["train", "features.afford", "-o", "model.afford"]):
            proc = run(args, d)
            assert proc.returncode == 0, proc.stderr.decode()[-500:]
        outs.append({f: (d / f).read_bytes() for f in ("effects.afford", "features.afford", "model.afford")})
    for f in outs[0]:
        assert outs[0][f] == outs[1][f], f"{f} differs between two identical runs"


# -- outputs: decided in one place, before any work ------------------------------------------

def _select(pipeline, out, cwd=None):
    from typer.testing import CliRunner

    from afford.app import app

    return CliRunner().invoke(app, ["select-features", str(pipeline / "effects.afford"), "-o", str(out), "--top", "4"])


def test_dev_null_discards_and_stays_a_device(pipeline):
    import stat

    result = _select(pipeline, "/dev/null")
    assert result.exit_code == 0, result.output
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


def test_dev_stdout_in_a_pipe_carries_the_artefact_alone(pipeline, tmp_path):
    from afford.artifacts import read_artifact

    proc = run(["select-features", str(pipeline / "effects.afford"), "-o", "/dev/stdout", "--top", "4"], tmp_path)
    assert proc.returncode == 0, proc.stderr.decode()[-300:]
    assert read_artifact("stdout", data=proc.stdout).kind == "features"  # the report went to stderr


def test_a_symlink_is_written_through_to_its_target(pipeline, tmp_path):
    from afford.artifacts import read_artifact

    (tmp_path / "real.afford").write_text("old")
    (tmp_path / "link.afford").symlink_to("real.afford")
    assert _select(pipeline, tmp_path / "link.afford").exit_code == 0
    assert (tmp_path / "link.afford").is_symlink()
    assert read_artifact(str(tmp_path / "real.afford")).kind == "features"


def test_a_fifo_is_streamed_to(pipeline, tmp_path):
    import threading

    from afford.artifacts import read_artifact

    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = {}
    reader = threading.Thread(target=lambda: got.setdefault("data", fifo.read_bytes()))
    reader.start()
    assert _select(pipeline, fifo).exit_code == 0
    reader.join(10)
    assert read_artifact("fifo", data=got["data"]).kind == "features"
    assert fifo.is_fifo()


@pytest.mark.parametrize("where, message", [
    ("trail/", "ends in '/': give a file name"),
    ("adir", "is a directory"),
    ("missing/x.afford", "does not exist"),
    ("/proc/x.afford", "cannot write /proc/x.afford: /proc refuses new files"),
])
def test_odd_outputs_are_refused_before_any_work(pipeline, tmp_path, monkeypatch, where, message):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "adir").mkdir()
    before = sorted(p.name for p in tmp_path.iterdir())
    result = _select(pipeline, where)
    assert result.exit_code == 1
    assert result.output.strip().splitlines() == [next(line for line in result.output.splitlines() if "error" in line)]
    assert message in result.output and ".tmp" not in result.output and "selecting" not in result.output
    assert sorted(p.name for p in tmp_path.iterdir()) == before


# -- signals: no orphaned workers, no temp files ---------------------------------------------

def _descendants(pid: int) -> list[int]:
    parents = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                parents[int(d)] = int(Path(f"/proc/{d}/stat").read_text().rsplit(")", 1)[1].split()[1])
            except (OSError, ValueError, IndexError):
                pass
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parents.items() if pp == p]
        out += kids
        todo += kids
    return out


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


def _explore_until_workers(tmp_path):
    import time

    proc = subprocess.Popen([*AFFORD, "explore", "--episodes", "400", "--workers", "2", "-o", "x.afford"],
                            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 60
    while time.time() < deadline:
        kids = _descendants(proc.pid)
        if len([k for k in kids if "popen_loky" in Path(f"/proc/{k}/cmdline").read_text(errors="ignore")]) >= 2:
            time.sleep(1.0)  # the workers have started their first chunks
            return proc, _descendants(proc.pid)
        time.sleep(0.2)
    proc.kill()
    pytest.fail("explore --workers 2 started no workers within 60 s")


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="PR_SET_PDEATHSIG is Linux's")
def test_kill_9_leaves_no_afford_process_behind(tmp_path):
    import signal
    import time

    proc, kids = _explore_until_workers(tmp_path)
    assert kids
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()
    deadline = time.time() + 5
    while time.time() < deadline and any(_alive(k) for k in kids):
        time.sleep(0.1)
    assert not [k for k in kids if _alive(k)], "workers outlived their parent"


def test_sigterm_is_an_interruption_and_leaves_no_temp_file(tmp_path):
    import signal

    proc, _ = _explore_until_workers(tmp_path)
    os.kill(proc.pid, signal.SIGTERM)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and b"error: interrupted; the output being written was discarded" in err and b"Traceback" not in err
    assert not list(tmp_path.iterdir())
