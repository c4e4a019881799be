"""Versioned artefacts: round trips, lineage, and every refusal of DESIGN.md section 3."""

from __future__ import annotations

import io
import json
import zipfile

import numpy as np
import pytest

from afford import artifacts as A
from afford.errors import AffordError


def _write(tmp_path, kind="interactions", arrays=None, meta=None, **kw):
    arrays = {"x": np.arange(6.0).reshape(2, 3), "i": np.array([1, 2], dtype=np.int16)} if arrays is None else arrays
    path = tmp_path / f"{kind}.afford"
    A.write_artifact(str(path), A.artifact_bytes(kind, arrays, meta or {"note": "hi"}, **kw))
    return path


def _rewrite(path, edit):
    """Rebuild the zip with ``edit(name, data) -> data`` applied to every member."""
    with zipfile.ZipFile(path) as zf:
        items = [(n, zf.read(n)) for n in zf.namelist()]
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zf:
        for n, d in items:
            out = edit(n, d)
            if out is not None:
                zf.writestr(n, out)
    path.write_bytes(buf.getvalue())


def _manifest_edit(reseal=False, **changes):
    """Change manifest fields; ``reseal`` also rewrites the manifest's own checksum, as a
    forger who knows the format would."""
    text = {}

    def edit(name, data):
        if name == "manifest.sha256" and reseal:
            return A._sha256(text["manifest"]).encode()
        if name != "manifest.json":
            return data
        m = json.loads(data)
        m.update(changes)
        text["manifest"] = json.dumps(m).encode()
        return text["manifest"]
    return edit


def test_round_trip_keeps_arrays_lineage_and_meta(tmp_path):
    parent = A.read_artifact(str(_write(tmp_path, "interactions")))
    path = _write(tmp_path, "effects", parents=[parent.parent_ref()], seed=4)
    art = A.read_artifact(str(path), "effects")
    assert np.array_equal(art.arrays["x"], np.arange(6.0).reshape(2, 3))
    assert art.arrays["i"].dtype == np.int16
    assert art.manifest["parents"] == [{"kind": "interactions", "sha256": parent.sha256}]
    assert art.manifest["seed"] == 4 and art.manifest["note"] == "hi"
    assert art.manifest["schema_version"] == A.SCHEMA_VERSION
    assert len(art.sha256) == 64


def test_equal_arrays_give_equal_member_bytes(tmp_path):
    (tmp_path / "a").mkdir()
    (tmp_path / "b").mkdir()
    a = A.read_artifact(str(_write(tmp_path / "a", "model")))
    b = A.read_artifact(str(_write(tmp_path / "b", "model")))
    assert a.manifest["members"] == b.manifest["members"]


@pytest.mark.parametrize("content", [b"", b"hello", b"PK\x03\x04 not really a zip"])
def test_not_an_afford_file(tmp_path, content):
    p = tmp_path / "x.afford"
    p.write_bytes(content)
    with pytest.raises(AffordError, match="not an afford file|empty"):
        A.read_artifact(str(p))


def test_an_unknown_kind_is_refused(tmp_path):
    path = _write(tmp_path)
    _rewrite(path, _manifest_edit(kind="banana"))
    with pytest.raises(AffordError, match="unknown artefact kind 'banana'"):
        A.read_artifact(str(path))


def test_a_zip_that_is_not_ours(tmp_path):
    p = tmp_path / "other.zip"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("manifest.json", json.dumps({"format": "something-else"}))
    with pytest.raises(AffordError, match="not an afford file"):
        A.read_artifact(str(p))


def test_wrong_kind_for_the_command(tmp_path):
    path = _write(tmp_path, "model")
    with pytest.raises(AffordError, match="is an artefact of kind 'model', but this command needs 'interactions'"):
        A.read_artifact(str(path), "interactions")


def test_newer_schema_asks_to_upgrade(tmp_path):
    path = _write(tmp_path)
    _rewrite(path, _manifest_edit(schema_version=A.SCHEMA_VERSION + 1))
    with pytest.raises(AffordError, match="upgrade afford"):
        A.read_artifact(str(path))


def test_older_schema_it_cannot_migrate(tmp_path, monkeypatch):
    path = _write(tmp_path)
    _rewrite(path, _manifest_edit(schema_version=0))
    with pytest.raises(AffordError, match="can no longer read"):
        A.read_artifact(str(path))


def test_an_edited_member_fails_its_checksum(tmp_path):
    path = _write(tmp_path)

    def flip(name, data):
        if name == "x.npy":
            data = bytearray(data)
            data[-1] ^= 0xFF
            return bytes(data)
        return data

    _rewrite(path, flip)
    with pytest.raises(AffordError, match="checksum mismatch in x.npy"):
        A.read_artifact(str(path))


def test_an_edited_manifest_fails_its_own_checksum(tmp_path):
    path = _write(tmp_path, seed=4)
    _rewrite(path, _manifest_edit(seed=5))
    with pytest.raises(AffordError, match="manifest.json does not match its checksum"):
        A.read_artifact(str(path))
    path = _write(tmp_path, seed=4)
    _rewrite(path, lambda n, d: None if n == "manifest.sha256" else d)
    with pytest.raises(AffordError, match="manifest checksum is missing"):
        A.read_artifact(str(path))


def test_schema_1_files_without_a_manifest_checksum_still_read(tmp_path):
    path = _write(tmp_path, seed=4)
    v1 = _manifest_edit(schema_version=1)
    _rewrite(path, lambda n, d: None if n == "manifest.sha256" else v1(n, d))
    art = A.read_artifact(str(path))
    assert art.manifest["seed"] == 4 and art.arrays["x"].shape == (2, 3)


def test_a_missing_member_is_refused(tmp_path):
    path = _write(tmp_path)
    _rewrite(path, lambda n, d: None if n == "i.npy" else d)
    with pytest.raises(AffordError, match="corrupt or was edited"):
        A.read_artifact(str(path))


def test_a_pickled_array_is_refused(tmp_path):
    path = _write(tmp_path)
    buf = io.BytesIO()
    np.save(buf, np.array([{"a": 1}], dtype=object), allow_pickle=True)
    evil = buf.getvalue()

    with zipfile.ZipFile(path) as zf:
        members = json.loads(zf.read("manifest.json"))["members"]
    members["x.npy"] = A._sha256(evil)
    reseal = _manifest_edit(reseal=True, members=members)
    _rewrite(path, lambda name, data: evil if name == "x.npy" else reseal(name, data))
    with pytest.raises(AffordError, match="needs pickle; refused"):
        A.read_artifact(str(path))


def test_object_arrays_are_never_written():
    with pytest.raises(ValueError, match="plain arrays"):
        A.artifact_bytes("interactions", {"x": np.array([None])}, {})


class NotTrusted:
    def __init__(self):
        self.payload = 1


def test_estimators_load_only_trusted_types(tmp_path):
    from sklearn.preprocessing import StandardScaler

    good = StandardScaler().fit(np.arange(6.0).reshape(3, 2))
    bad = NotTrusted()
    path = tmp_path / "m.afford"
    A.write_artifact(str(path), A.artifact_bytes("model", {}, {}, blobs={
        "good": A.dump_estimator(good), "bad": A.dump_estimator(bad)}))
    art = A.read_artifact(str(path), "model")
    loaded = art.estimator("good", trusted=[])
    assert np.allclose(loaded.mean_, good.mean_)
    with pytest.raises(AffordError, match="untrusted type tests.test_artifacts.NotTrusted"):
        art.estimator("bad", trusted=[])
    # trusting it explicitly is the caller's decision
    assert art.estimator("bad", trusted=["tests.test_artifacts.NotTrusted"]).payload == 1


def test_writes_are_atomic(tmp_path, monkeypatch):
    path = _write(tmp_path)
    before = path.read_bytes()

    class Boom(Exception):
        pass

    def explode(*a, **k):
        raise Boom()

    monkeypatch.setattr(A.os, "replace", explode)
    with pytest.raises(Boom):
        A.write_artifact(str(path), b"new content")
    assert path.read_bytes() == before
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left behind


def test_missing_file_and_directory(tmp_path):
    with pytest.raises(AffordError, match="does not exist"):
        A.read_artifact(str(tmp_path / "nope.afford"))
    with pytest.raises(AffordError, match="is a directory"):
        A.read_artifact(str(tmp_path))
    with pytest.raises(AffordError, match="does not exist"):
        A.write_artifact(str(tmp_path / "no" / "dir.afford"), b"x")


def _old_names(blob: bytes) -> bytes:
    """A skops blob as afford wrote it before schema 3, when ``learn`` was a top-level package."""
    with zipfile.ZipFile(io.BytesIO(blob)) as zin:
        items = [(i.filename, zin.read(i.filename)) for i in zin.infolist()]
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w") as zout:
        for n, d in items:
            zout.writestr(n, d.replace(b'"afford.learn.', b'"learn.') if n == "schema.json" else d)
    return buf.getvalue()


def test_schema_2_models_with_the_old_package_names_still_load(tmp_path):
    from afford.learn import TRUSTED_TYPES, AffordancePredictor

    rng = np.random.default_rng(0)
    X = rng.normal(size=(60, 3))
    y = (X[:, 0] > 0).astype(int)
    fitted = AffordancePredictor(kernel="linear", cv=3, random_state=0).fit(X, y)
    old = _old_names(A.dump_estimator(fitted))
    assert b'"learn.predictors"' in old and b"afford.learn" not in old
    path = tmp_path / "old.afford"
    path.write_bytes(A.artifact_bytes("model", {}, {}, blobs={"predictor": old}))
    # written by this afford, the old names are not trusted: renaming is for older files only
    with pytest.raises(AffordError, match="untrusted type learn.predictors.AffordancePredictor"):
        A.read_artifact(str(path)).estimator("predictor", TRUSTED_TYPES)
    _rewrite(path, _manifest_edit(reseal=True, schema_version=2))
    loaded = A.read_artifact(str(path)).estimator("predictor", TRUSTED_TYPES)
    assert type(loaded) is AffordancePredictor
    assert np.array_equal(loaded.predict_proba(X), fitted.predict_proba(X))
