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


def _cpu_seconds(pid: int) -> float:
    """CPU time (user + system) process ``pid`` has used; 0 once it is gone."""
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    except OSError:
        return 0.0
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _explore_until_workers(tmp_path):
    import time

    # 4000 episodes: on a fast machine 400 took 5 s, so the signal could land as the run
    # ended (the tests kill it long before it ends)
    proc = subprocess.Popen([*AFFORD, "explore", "--episodes", "4000", "--workers", "2", "-o", "x.afford"],
                            cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.time() + 90
    while time.time() < deadline:
        kids = _descendants(proc.pid)
        workers = [k for k in kids if "popen_loky" in Path(f"/proc/{k}/cmdline").read_text(errors="ignore")]
        # a worker asks to die with its parent when it starts its first chunk, after its
        # imports (about 1.5 s of CPU); on a loaded machine a fixed sleep was not enough
        if len(workers) >= 2 and all(_cpu_seconds(k) >= 4.0 for k in workers):
            return proc, _descendants(proc.pid)
        time.sleep(0.2)
    proc.kill()
    pytest.fail("explore --workers 2 started no busy workers within 90 s")


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
    assert proc.returncode == 130 and b"error: interrupted; " in err and b"Traceback" not in err
    # no temporary file and no output; at most the journal of finished episodes (test_distributed.py)
    assert [p.name for p in tmp_path.iterdir()] in ([], ["x.afford.partial"])


def _raise_from_interruption(kind: str):
    """A command whose work an interruption broke: the error a library made of it."""
    from afford.errors import Interrupted

    try:
        raise Interrupted("interrupted; 3 finished episodes are kept") if kind == "kept" else KeyboardInterrupt
    except KeyboardInterrupt as exc:
        if kind == "context":
            raise OSError("handle is closed")  # raised while handling it: its __context__
        raise ImportError("initialization failed") from exc  # what open3d's import makes of it


@pytest.mark.parametrize("kind", ["cause", "context", "kept"])
def test_an_error_an_interruption_caused_exits_130_with_one_sentence(kind, capsys):
    """A SIGTERM that landed while open3d was being imported once ended in an ImportError's
    traceback and exit 1; an error whose cause or context is an interruption is the interruption."""
    import typer

    from afford.app import _guarded

    with pytest.raises(typer.Exit) as exit_:
        _guarded(lambda: _raise_from_interruption(kind))()
    err = capsys.readouterr().err
    assert exit_.value.exit_code == 130
    assert err.strip() == ("error: interrupted; 3 finished episodes are kept" if kind == "kept"
                           else "error: interrupted; the output being written was discarded")


def test_a_sigterm_inside_an_import_waits_for_the_import(tmp_path):
    """A signal that lands while a module is being imported is raised once the import is done
    (inside a compiled module's initialisation it broke the interpreter)."""
    (tmp_path / "slow_module.py").write_text(
        "import os, signal, time\nos.kill(os.getpid(), signal.SIGTERM)\ntime.sleep(0.3)\nDONE = True\n")
    script = ("import signal, sys, time\nfrom afford.interrupt import terminate\nsignal.signal(signal.SIGTERM, terminate)\n"
              "try:\n    import slow_module\n    print('imported', slow_module.DONE, flush=True)\n    time.sleep(10)\n"
              "    print('never interrupted')\nexcept KeyboardInterrupt:\n    print('interrupted', 'slow_module' in sys.modules)\n")
    proc = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True, text=True, timeout=60,
                          env={**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), *sys.path])})
    assert proc.stdout.split() == ["imported", "True", "interrupted", "True"], proc.stderr[-500:]


def test_the_entry_point_turns_an_interruption_before_any_command_into_130(monkeypatch, capsys):
    """The console entry point installs the handlers, then imports the commands: an
    interruption that lands there (or as a command ends) is exit 130 with one sentence, not a
    traceback nor death by the signal."""
    import signal

    import afford.app as cli
    from afford import interrupt

    def interrupted(argv=None):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "main", interrupted)
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with pytest.raises(SystemExit) as exit_:
            interrupt.main([])
        assert signal.getsignal(signal.SIGTERM) is interrupt.terminate
    finally:
        for s, handler in handlers.items():
            signal.signal(s, handler)
    assert exit_.value.code == 130 and capsys.readouterr().err.strip() == "error: interrupted"


def test_an_interruption_waits_for_steps_that_must_all_happen():
    """Making and removing the output's probe file is one step: a SIGTERM between the two left
    the probe behind. Held, the signal is delivered once the step is done."""
    script = ("import os, signal, time\nfrom afford.interrupt import terminate, uninterrupted\n"
              "signal.signal(signal.SIGTERM, terminate)\ndone = []\ntry:\n    with uninterrupted():\n"
              "        os.kill(os.getpid(), signal.SIGTERM)\n        time.sleep(0.2)\n        done.append(1)\n"
              "    time.sleep(10)\n    print('never interrupted')\nexcept KeyboardInterrupt:\n    print('interrupted after', len(done))\n")
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert proc.stdout.split() == ["interrupted", "after", "1"], proc.stderr[-500:]


def test_an_error_with_no_interruption_behind_it_stays_an_error(capsys):
    import typer

    from afford.app import _guarded

    def command():
        try:
            raise ValueError("parsing")
        except ValueError as exc:
            raise OSError("disk full") from exc

    with pytest.raises(typer.Exit) as exit_:
        _guarded(command)()
    assert exit_.value.exit_code == 1 and capsys.readouterr().err == "error: disk full\n"


def test_an_interruption_outside_any_command_still_says_so(monkeypatch, capsys):
    """Typer turns a Ctrl-C during its own parsing into exit 130 with no word; main adds one."""
    import afford.app as cli

    def interrupted_while_parsing(args=None):
        raise SystemExit(130)

    import signal

    monkeypatch.setattr(cli, "app", interrupted_while_parsing)
    monkeypatch.setattr(cli, "_reported", [False])
    handlers = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        with pytest.raises(SystemExit) as exit_:
            cli.main([])
    finally:  # main ignores both signals as it ends; this process goes on
        for s, handler in handlers.items():
            signal.signal(s, handler)
    assert exit_.value.code == 130 and capsys.readouterr().err.strip() == "error: interrupted"


# -- forged artefacts: checksums and seal recomputed, as a forger who knows the format would --

def forge(src: Path, dst: Path, members: dict | None = None, manifest=None, seal: bool = True) -> Path:
    """A copy of ``src`` with ``members`` replaced (bytes) or removed (None), ``manifest(m)``
    applied, every checksum recomputed and (``seal``) the manifest resealed."""
    import io
    import json
    import zipfile

    from afford.artifacts import _sha256

    with zipfile.ZipFile(src) as zf:
        items = {n: zf.read(n) for n in zf.namelist()}
    m = json.loads(items.pop("manifest.json"))
    items.pop("manifest.sha256", None)
    for name, data in (members or {}).items():
        if data is None:
            items.pop(name, None)
        else:
            items[name] = data
    m["members"] = {n: _sha256(d) for n, d in items.items()}
    if manifest is not None:
        manifest(m)
    text = json.dumps(m).encode()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        zf.writestr("manifest.json", text)
        if seal:
            zf.writestr("manifest.sha256", _sha256(text))
        for n, d in items.items():
            zf.writestr(n, d)
    dst.write_bytes(buf.getvalue())
    return dst


def _npy(array) -> bytes:
    import io

    import numpy as np

    buf = io.BytesIO()
    np.save(buf, array, allow_pickle=False)
    return buf.getvalue()


def _huge_header() -> bytes:
    import io

    import numpy as np

    buf = io.BytesIO()
    np.lib.format.write_array_header_1_0(buf, {"descr": "<f4", "fortran_order": False, "shape": (10**12, 43)})
    return buf.getvalue() + b"\0" * 64


def _skops(estimator) -> bytes:
    import skops.io as sio

    return sio.dumps(estimator)


def _nested_swap(blob: bytes) -> bytes:
    """A predictor whose inner scaler is swapped for another, skops-trusted, estimator."""
    import io
    import zipfile

    with zipfile.ZipFile(io.BytesIO(blob)) as zin:
        items = {i.filename: zin.read(i.filename) for i in zin.infolist()}
    items["schema.json"] = (items["schema.json"].replace(b'"sklearn.preprocessing._data"', b'"sklearn.neighbors._classification"')
                            .replace(b'"StandardScaler"', b'"KNeighborsClassifier"'))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zout:
        for n, d in items.items():
            zout.writestr(n, d)
    return buf.getvalue()


def _skops_wide(model) -> bytes:
    """A real predictor, fitted on more inputs than the model's lift predictor reads."""
    import numpy as np

    from afford.artifacts import dump_estimator
    from afford.learn import AffordancePredictor

    width = model.arrays["selected.lift"].size + 3
    rng = np.random.default_rng(0)
    X = rng.normal(size=(40, width))
    return dump_estimator(AffordancePredictor(kernel="linear", cv=2, random_state=0).fit(X, (X[:, 0] > 0).astype(int)))


def _cases(p: Path):
    import numpy as np
    from sklearn.linear_model import LogisticRegression

    from afford.artifacts import read_artifact

    model = read_artifact(str(p / "model.afford"))
    logistic = LogisticRegression().fit(np.array([[0.0], [1.0], [0.2], [0.9]]), [0, 1, 0, 1])
    return [
        ("behaviours-integers", "train.afford", {}, lambda m: m.update(behaviors=[1, 2, 3, 4]), ["inspect"]),
        ("categories-number", "model.afford", {}, lambda m: m.update(categories=7), ["inspect"]),
        ("entities-strings", "train.afford", {"entities.npy": _npy(np.array([["a"] * 43] * 3))}, None, ["inspect"]),
        ("huge-header", "train.afford", {"entities.npy": _huge_header()}, None, ["inspect"]),
        ("selected-out-of-range", "features.afford", {"selected.push-forward.npy": _npy(np.array([0, 999], np.int32))},
         None, ["train", "-o", "{out}"]),
        ("model-selected-out-of-range", "model.afford", {"selected.lift.npy": _npy(np.array([4000], np.int32))},
         None, ["predict", "--seed", "1"]),
        ("effects-in-predictor-slot", "model.afford",
         {"predictor.lift.skops": model.blobs["effects.lift"]}, None, ["predict", "--seed", "1"]),
        ("logistic-in-predictor-slot", "model.afford", {"predictor.lift.skops": _skops(logistic)}, None,
         ["predict", "--seed", "1"]),
        ("nested-swap", "model.afford", {"predictor.lift.skops": _nested_swap(model.blobs["predictor.lift"])}, None,
         ["predict", "--seed", "1"]),
        ("train-x-shape", "model.afford", {"train_X.lift.npy": _npy(np.zeros((5, 2), np.float32))}, None,
         ["evaluate", "{test}", "--baselines"]),
        ("predictor-swapped-between-behaviours", "model.afford", {"predictor.lift.skops": _skops_wide(model)}, None,
         ["plan", "--seed", "1", "--goal", "*:visibility=0"]),
        ("categories-count", "model.afford", {}, lambda m: m["categories"]["lift"].pop(), ["predict", "--seed", "1"]),
        ("prototypes-strings", "model.afford", {"prototypes.lift.npy": _npy(np.array([["a"] * 43] * 2))}, None,
         ["predict", "--seed", "1"]),
        ("edited-counts", "train.afford", {}, lambda m: m.update(n_interactions=9999, n_episodes=-3), ["inspect"]),
        ("missing-member", "model.afford", {"selected.push-forward.npy": None}, None, ["predict", "--seed", "1"]),
        ("member-effects-short", "model.afford", {"members_E.lift.npy": _npy(np.zeros((3, 43), np.float32))}, None,
         ["predict", "--seed", "1"]),
        ("member-effects-missing", "model.afford", {"members_Z.push-left.npy": None}, None,
         ["plan", "--seed", "1", "--goal", "*:visibility=0"]),
        ("member-effects-category", "model.afford",
         {"members_labels.lift.npy": _npy(np.full(model.arrays["members_labels.lift"].shape, 99, np.int16))}, None,
         ["predict", "--seed", "1"]),
        ("member-effects-meta", "model.afford", {}, lambda m: m["member_effects"]["lift"].update(k="many"),
         ["predict", "--seed", "1"]),
        ("scene-clustering-kmax", "train.afford", {}, lambda m: m["scene"].update(clustering={"k_max": "many"}),
         ["cluster", "-o", "{out}"]),
        ("scene-clustering-channels", "train.afford", {}, lambda m: m["scene"].update(clustering={"channels": "cp"}),
         ["cluster", "-o", "{out}"]),
        ("scene-learner-score", "effects.afford", {}, lambda m: m["scene"].update(learner={"score": "auc"}),
         ["select-features", "-o", "{out}"]),
    ]


@pytest.fixture(scope="module")
def forged(pipeline, tmp_path_factory):
    d = tmp_path_factory.mktemp("forged")
    out = {}
    for name, src, members, manifest, cmd in _cases(pipeline):
        out[name] = (forge(pipeline / src, d / f"{name}.afford", members, manifest), cmd)
    return out


@pytest.mark.parametrize("case", [
    "behaviours-integers", "categories-number", "entities-strings", "huge-header", "selected-out-of-range",
    "model-selected-out-of-range", "effects-in-predictor-slot", "logistic-in-predictor-slot", "nested-swap",
    "train-x-shape", "predictor-swapped-between-behaviours", "categories-count", "prototypes-strings",
    "edited-counts",
    "missing-member", "member-effects-short", "member-effects-missing", "member-effects-category", "member-effects-meta",
    "scene-clustering-kmax", "scene-clustering-channels", "scene-learner-score"])
def test_a_forged_file_is_one_sentence_and_exit_1(forged, pipeline, tmp_path, case):
    from typer.testing import CliRunner

    from afford.app import app

    path, cmd = forged[case]
    before = path.read_bytes()
    args = [cmd[0], str(path)] + [a.format(out=tmp_path / "o.afford", test=pipeline / "test.afford") for a in cmd[1:]]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, (case, result.output, result.exception)
    assert isinstance(result.exception, SystemExit), f"{case}: {result.exception!r}"  # no traceback
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and str(path) in errors[0], (case, result.output)
    assert path.read_bytes() == before and not (tmp_path / "o.afford").exists()


def test_unsupported_compression_is_corrupt(pipeline, tmp_path):
    from afford.artifacts import read_artifact
    from afford.errors import AffordError

    raw = bytearray((pipeline / "train.afford").read_bytes())
    at = raw.find(b"PK\x01\x02")
    while at >= 0:  # every central-directory entry says: compression method 99
        raw[at + 10:at + 12] = (99).to_bytes(2, "little")
        at = raw.find(b"PK\x01\x02", at + 4)
    (tmp_path / "c.afford").write_bytes(bytes(raw))
    with pytest.raises(AffordError, match="is corrupt"):
        read_artifact(str(tmp_path / "c.afford"))


def test_a_relabelled_schema_1_file_is_refused_and_a_real_one_is_unsealed(pipeline, tmp_path):
    from afford.artifacts import read_artifact
    from afford.errors import AffordError

    path = forge(pipeline / "train.afford", tmp_path / "v1.afford", manifest=lambda m: m.update(schema_version=1),
                 seal=False)
    with pytest.raises(AffordError, match="claims artefact schema 1 but carries"):
        read_artifact(str(path))
    old = forge(pipeline / "train.afford", tmp_path / "old.afford", seal=False, manifest=lambda m: [
        m.update(schema_version=1), *(m.pop(k, None) for k in ("label_source", "result_names", "n_entities"))])
    art = read_artifact(str(old))
    assert not art.sealed


# -- an output that is one of the command's inputs: refused before any work ------------------

@pytest.mark.parametrize("cmd, src, out", [
    (["export", "{x}", "-o", "{x}"], "train.afford", "same"),
    (["export", "{x}", "-o", "{x}", "-f", "parquet"], "train.afford", "same"),
    (["train", "{x}", "-o", "{dot}"], "features.afford", "same"),
    (["cluster", "{x}", "-o", "{x}"], "train.afford", "same"),
    (["select-features", "{x}", "-o", "{x}"], "effects.afford", "same"),
    (["merge", "{x}", "-o", "{x}"], "train.afford", "same"),
    (["train", "{link}", "-o", "{x}"], "features.afford", "link"),
    (["export", "{x}", "-o", "{hard}"], "train.afford", "hard"),
])
def test_an_output_that_is_an_input_is_refused_before_any_work(pipeline, tmp_path, monkeypatch, cmd, src, out):
    from typer.testing import CliRunner

    from afford.app import app

    monkeypatch.chdir(tmp_path)
    x = tmp_path / src
    shutil.copy(pipeline / src, x)
    (tmp_path / "link.afford").symlink_to(src)
    os.link(x, tmp_path / "hard.afford")
    before = x.read_bytes()
    listing = sorted(p.name for p in tmp_path.iterdir())
    args = [a.format(x=src, dot=f"./{src}", link="link.afford", hard="hard.afford") for a in cmd]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, (args, result.output)
    assert isinstance(result.exception, SystemExit)
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and "is an input of this command; give another output path" in errors[0], result.output
    assert x.read_bytes() == before
    assert sorted(p.name for p in tmp_path.iterdir()) == listing


# -- forged learning files the chain used to take (checksums recomputed) ---------------------

def _shifted_categories(p: Path, shift=50, as_float=False):
    import numpy as np

    from afford.artifacts import read_artifact

    cat = read_artifact(str(p / "effects.afford")).arrays["category"].astype(np.int16)
    cat = np.where(cat >= 0, cat + shift, cat)
    return _npy(cat.astype(np.float32) if as_float else cat)


def _non_finite(p: Path, member: str, value: float):
    import numpy as np

    from afford.artifacts import read_artifact

    a = read_artifact(str(p / "model.afford")).arrays[member].copy()
    a.flat[0] = value
    return _npy(a)


@pytest.mark.parametrize("case, src, members, cmd, message", [
    ("selected-empty", "features.afford", lambda p: {"selected.push-forward.npy": _npy(__import__("numpy").zeros(0, "int32"))},
     ["train", "-o", "{out}"], "selected.push-forward is empty; it is corrupt or was edited"),
    ("categories-shifted", "effects.afford", lambda p: {"category.npy": _shifted_categories(p)},
     ["train", "-o", "{out}"], "category gives"),
    ("categories-float", "effects.afford", lambda p: {"category.npy": _shifted_categories(p, 0, True)},
     ["train", "-o", "{out}"], "where whole category numbers belong"),
    ("categories-shifted-select", "effects.afford", lambda p: {"category.npy": _shifted_categories(p)},
     ["select-features", "-o", "{out}"], "category gives"),
    ("prototypes-nan", "model.afford", lambda p: {"prototypes.lift.npy": _non_finite(p, "prototypes.lift", float("nan"))},
     ["predict", "--seed", "1"], "prototypes.lift holds values that are not finite"),
    ("members-inf", "model.afford", lambda p: {"members_E.lift.npy": _non_finite(p, "members_E.lift", float("inf"))},
     ["predict", "--seed", "1"], "members_E.lift holds values that are not finite"),
])
def test_a_forged_learning_file_is_refused_when_read(pipeline, tmp_path, case, src, members, cmd, message):
    from typer.testing import CliRunner

    from afford.app import app

    path = forge(pipeline / src, tmp_path / f"{case}.afford", members(pipeline))
    before = path.read_bytes()
    args = [cmd[0], str(path)] + [a.format(out=tmp_path / "o.afford") for a in cmd[1:]]
    result = CliRunner().invoke(app, args)
    assert result.exit_code == 1, (case, result.output, result.exception)
    assert isinstance(result.exception, SystemExit), f"{case}: {result.exception!r}"
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and str(path) in errors[0] and message in errors[0], (case, result.output)
    assert path.read_bytes() == before and not (tmp_path / "o.afford").exists()



@pytest.mark.parametrize("case", [
    "selected-out-of-range", "model-selected-out-of-range", "effects-in-predictor-slot", "logistic-in-predictor-slot",
    "nested-swap", "train-x-shape", "predictor-swapped-between-behaviours", "categories-count", "prototypes-strings",
    "missing-member", "member-effects-short", "member-effects-category", "member-effects-meta"])
def test_inspect_verifies_only_what_the_consuming_commands_would_open(forged, case):
    from typer.testing import CliRunner

    from afford.app import app

    path, _ = forged[case]
    result = CliRunner().invoke(app, ["inspect", str(path)])
    assert result.exit_code == 1 and "verified" not in result.output, (case, result.output)
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and str(path) in errors[0], (case, result.output)

# -- pddl's output directory -----------------------------------------------------------------

@pytest.mark.parametrize("where, message", [
    ("-", "pddl writes four files, not one stream; give a directory"),
    ("", "give a directory for the PDDL files"),
])
def test_pddl_refuses_a_stream_or_no_directory(pipeline, tmp_path, monkeypatch, where, message):
    from typer.testing import CliRunner

    from afford.app import app

    monkeypatch.chdir(tmp_path)
    result = CliRunner().invoke(app, ["pddl", str(pipeline / "model.afford"), "--goal", "*:visibility=0",
                                      "--seed", "1", "-o", where])
    assert result.exit_code == 1, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert len(errors) == 1 and message in errors[0], result.output
    assert list(tmp_path.iterdir()) == []


def test_pddl_says_it_cannot_write_a_directory_it_may_not_make(pipeline, tmp_path, monkeypatch):
    """As root nothing is denied, so the operating system's refusal is simulated."""
    from typer.testing import CliRunner

    from afford.app import app

    def denied(self, *a, **kw):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "mkdir", denied)
    out = tmp_path / "pddl"
    result = CliRunner().invoke(app, ["pddl", str(pipeline / "model.afford"), "--goal", "*:visibility=0",
                                      "--seed", "1", "-o", str(out)])
    assert result.exit_code == 1, result.output
    errors = [line for line in result.output.splitlines() if line.startswith("error:")]
    assert errors == [f"error: cannot write {out}: permission denied"], result.output


# -- reports and wording ---------------------------------------------------------------------

def test_cluster_reports_the_interactions_it_dropped(pipeline, tmp_path):
    import json

    from typer.testing import CliRunner

    from afford.app import app

    runner = CliRunner()
    args = ["cluster", str(pipeline / "test.afford"), "-o", str(tmp_path / "e.afford"), "--seed", "1"]
    data = json.loads(runner.invoke(app, [*args, "--json"]).stdout)
    human = runner.invoke(app, args)
    assert human.exit_code == 0, human.output
    for name, b in data["behaviors"].items():
        total = b["pruned_rows"] + sum(c["count"] for c in b["categories"])
        assert f"{name}: {b['pruned_rows']} of {total} interactions dropped (rare kinds)" in human.output


def test_cluster_advice_names_the_command_line_options(pipeline, tmp_path):
    from typer.testing import CliRunner

    from afford.app import app

    result = CliRunner().invoke(app, ["cluster", str(pipeline / "test.afford"), "-o", str(tmp_path / "e.afford"),
                                      "--min-fraction", "0.5"])
    assert result.exit_code == 1, result.output
    assert "lower --min-fraction" in result.output
    assert "min_fraction" not in result.output and "predictability_threshold" not in result.output


def test_merging_one_shard_says_one_shard(pipeline, tmp_path):
    from typer.testing import CliRunner

    from afford.app import app
    from afford.artifacts import read_artifact

    episodes = read_artifact(str(pipeline / "train.afford")).arrays["episode"]
    shard = forge(pipeline / "train.afford", tmp_path / "shard.afford",
                  manifest=lambda m: m.update(episodes={"start": 0, "stop": int(episodes.max()) + 1}))
    result = CliRunner().invoke(app, ["merge", str(shard), "-o", str(tmp_path / "m.afford")])
    assert result.exit_code == 0, result.output
    assert "merged 1 shard:" in result.output


def test_the_python_api_refuses_an_output_that_is_an_input_too(pipeline, tmp_path):
    from afford import api
    from afford.errors import AffordError

    for call, src in ((lambda p: api.train(p, p), "features.afford"), (lambda p: api.cluster(p, p), "train.afford"),
                      (lambda p: api.select_features(p, p), "effects.afford"), (lambda p: api.merge([p], p), "train.afford")):
        x = tmp_path / src
        shutil.copy(pipeline / src, x)
        before = x.read_bytes()
        with pytest.raises(AffordError, match="is an input of this command"):
            call(str(x))
        assert x.read_bytes() == before


@pytest.mark.parametrize("extra, words", [
    (["--method", "kmeans", "--kmax", "3"], "--kmax bounds X-means"),
    (["--prune", "predictability", "--min-fraction", "0.2"], "--min-fraction goes with --prune frequency"),
    (["--method", "kmeans", "--k", "3", "--k", "4"], "--k is given twice for every behaviour"),
    (["--method", "kmeans", "--k", "lift=3", "--k", "lift=2"], "--k is given twice for lift"),
])
def test_cluster_refuses_an_option_it_would_ignore(pipeline, tmp_path, extra, words):
    from tests.clitools import fails

    out = tmp_path / "e.afford"
    assert words in fails(["cluster", str(pipeline / "train.afford"), "-o", str(out), *extra], code=2)
    assert not out.exists()


def test_a_manifest_without_its_schema_is_named_without_python_words(pipeline, tmp_path):
    from tests.clitools import fails

    path = forge(pipeline / "train.afford", tmp_path / "noschema.afford", manifest=lambda m: m.pop("schema"))
    msg = fails(["cluster", str(path), "-o", str(tmp_path / "e.afford")])
    assert "lacks 'schema'" in msg and "KeyError" not in msg, msg
