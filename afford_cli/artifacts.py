"""Versioned artefact files: one zip per artefact, checked on every read.

Layout (DESIGN.md section 3)::

    manifest.json   format, kind, schema_version, afford_version, created, command, seed,
                    parents [{kind, sha256}], members {name: sha256}, and report data
    manifest.sha256 the sha256 of manifest.json's bytes (schema 2 on): an edited manifest,
                    not only an edited member, is caught
    <name>.npy      arrays, always read with allow_pickle=False
    <name>.skops    fitted estimators (skops.io), loaded with an explicit trusted-type list

Writing goes to a temporary file beside the target and is renamed into place, so a crash
never leaves half a file; ``-`` means stdout (or stdin when reading). Reading refuses, with
one sentence, anything that is not an afford file, the wrong kind, a newer or unmigratable
schema, a member whose checksum does not match, or an estimator holding an untrusted type.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import io
import json
import os
import re
import stat
import sys
import tempfile
import zipfile
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from afford.errors import AffordError
from afford.interrupt import uninterrupted

__all__ = [
    "SCHEMA_VERSION", "MIN_SCHEMA_VERSION", "Artifact", "write_artifact", "read_artifact",
    "artifact_bytes", "dump_estimator", "load_estimator", "check_output", "check_not_input", "writes_stdout", "output_is_file",
]

FORMAT = "afford"
#: Bump when the layout changes; teach ``_migrate`` the step from the previous one.
#: 2: the manifest's own checksum (``manifest.sha256``).
#: 3: estimators name their classes by the one import name (``afford.learn.predictors``,
#: was ``learn.predictors``); :meth:`Artifact.estimator` renames them in older files.
SCHEMA_VERSION = 3
MIN_SCHEMA_VERSION = 1
KINDS = ("interactions", "effects", "features", "model")
_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
_SEAL = "manifest.sha256"


def _version() -> str:
    from afford import __version__

    return __version__


def _created() -> str:
    """The write time, UTC to the second; ``SOURCE_DATE_EPOCH`` (the reproducible-builds
    convention) fixes it, so that two runs can give byte-identical files."""
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    when = (_dt.datetime.fromtimestamp(int(epoch), _dt.timezone.utc) if epoch and epoch.isdigit()
            else _dt.datetime.now(_dt.timezone.utc))
    return when.strftime("%Y-%m-%dT%H:%M:%SZ")


def _sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def _npy_bytes(array: np.ndarray) -> bytes:
    buf = io.BytesIO()
    np.save(buf, np.ascontiguousarray(array), allow_pickle=False)
    return buf.getvalue()


@dataclass
class Artifact:
    """An artefact read from (or about to be written to) a file."""

    kind: str
    manifest: dict[str, Any]
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    blobs: dict[str, bytes] = field(default_factory=dict)   # raw .skops members
    sha256: str = ""
    source: str = ""
    sealed: bool = True   # the manifest's own checksum was there and matched (schema 2 on)

    def __post_init__(self):
        self.arrays = _Members(self.arrays, self.source, ".npy")
        self.blobs = _Members(self.blobs, self.source, ".skops")

    def parent_ref(self) -> dict[str, str]:
        return {"kind": self.kind, "sha256": self.sha256}

    def estimator(self, name: str, trusted: list[str], expect: type | None = None,
                  parts: frozenset[str] | None = None):
        """Load estimator member ``name`` with skops, refusing any type not trusted, one that
        is not of type ``expect`` (a trusted type in the wrong slot is still wrong), and, given
        ``parts``, one built of any class outside them (checked before anything is built)."""
        if name not in self.blobs:
            raise AffordError(f"{self.source} holds no estimator named {name!r}; it is corrupt or was edited")
        blob = self.blobs[name]
        if self.manifest.get("schema_version", SCHEMA_VERSION) < 3:
            blob = _rename_modules(blob, f"{self.source}: {name}")
        if parts is not None:
            _check_parts(blob, f"{self.source}: {name}", parts, expect.__name__ if expect else "estimator")
        obj = load_estimator(blob, f"{self.source}: {name}", trusted)
        if expect is not None and type(obj) is not expect:
            raise AffordError(f"{self.source}: {name} holds {_a(type(obj).__name__)} where {_a(expect.__name__)} "
                              "belongs; it was edited")
        return obj


@contextmanager
def reading(art: "Artifact"):
    """Reading an artefact's structure: a manifest or array that does not fit what its kind
    holds (a forged file, with its checksums recomputed) is one sentence, not a traceback."""
    try:
        yield
    except AffordError:
        raise
    except (TypeError, KeyError, IndexError, AttributeError, ValueError) as exc:
        detail = str(exc) if isinstance(exc, ValueError) and str(exc) else type(exc).__name__
        raise AffordError(f"{art.source} is corrupt or was edited: what it holds does not fit {_a(art.kind)} "
                          f"artefact ({detail})") from None


def _a(word: str) -> str:
    return f"{'an' if word[:1].lower() in 'aeiou' else 'a'} {word}"


#: skops nodes that hold data, not objects to build
_DATA_NODES = {"NdArrayNode", "JsonNode", "DictNode", "ListNode", "TupleNode", "SetNode", "SliceNode",
               "DTypeNode", "BytesNode", "BytearrayNode"}


def _skops_open(blob: bytes, where: str) -> tuple[Any, dict[str, bytes]]:
    """A skops blob's parsed ``schema.json`` and its other members."""
    try:
        with zipfile.ZipFile(io.BytesIO(blob)) as zf:
            members = {info.filename: zf.read(info.filename) for info in zf.infolist()}
        return json.loads(members.pop("schema.json")), members
    except (zipfile.BadZipFile, KeyError, ValueError, OSError, NotImplementedError, EOFError):
        raise AffordError(f"{where} is not a readable estimator") from None


def _skops_pack(schema, members: dict[str, bytes]) -> bytes:
    """A skops blob of ``schema`` and ``members``, canonical: entries in name order, one
    fixed time, so equal contents give equal bytes."""
    out = {"schema.json": json.dumps(schema, indent=2).encode(), **members}
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_STORED) as zout:
        for name in sorted(out):
            info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
            info.external_attr = 0o644 << 16
            zout.writestr(info, out[name])
    return buf.getvalue()


def _nodes(schema):
    """Every dict (skops node) in a skops schema."""
    todo = [schema]
    while todo:
        node = todo.pop()
        if isinstance(node, list):
            todo.extend(node)
        elif isinstance(node, dict):
            todo.extend(node.values())
            yield node


def _check_parts(blob: bytes, where: str, parts: frozenset[str], what: str) -> None:
    """Refuse a skops blob that would build a class outside ``parts`` (type references may
    name builtins and numpy types only)."""
    schema, _ = _skops_open(blob, where)
    for node in _nodes(schema):
        loader = node.get("__loader__")
        if loader is None or loader in _DATA_NODES:
            continue
        name = f"{node.get('__module__')}.{node.get('__class__')}"
        ok = (str(node.get("__module__")).split(".")[0] in ("builtins", "numpy") if loader == "TypeNode"
              else name in parts)
        if not ok:
            raise AffordError(f"{where} would build {name}, which {_a(what)} is never made of; it was edited")


class _Members(dict):
    """An artefact's members: a missing one is one sentence naming the file and the member."""

    def __init__(self, items, source: str, suffix: str):
        super().__init__(items)
        self.source, self.suffix = source, suffix

    def __missing__(self, key):
        raise AffordError(f"{self.source} lacks the member {key}{self.suffix}; it is corrupt or was edited")


#: Packages that were top-level before schema 3 and now live under ``afford``.
_OLD_PACKAGES = ("sim", "features", "learn", "plan")


def _rename_modules(blob: bytes, where: str) -> bytes:
    """A skops blob from before schema 3 with its classes' modules renamed (``learn.x`` ->
    ``afford.learn.x``); skops keeps each object's module in ``schema.json``."""
    schema, members = _skops_open(blob, where)
    for node in _nodes(schema):
        module = node.get("__module__")
        if isinstance(module, str) and module.split(".")[0] in _OLD_PACKAGES:
            node["__module__"] = f"afford.{module}"
    return _skops_pack(schema, members)


def dump_estimator(estimator) -> bytes:
    """skops bytes of ``estimator``, canonical: the same estimator gives the same bytes.

    skops names each object (``__id__``) and each array member (``<id>.npy``) by its Python
    ``id()`` and stamps the zip entries with the wall clock, so equal estimators gave other
    bytes every run. Here ids are numbered in the order the schema first meets them (a
    depth-first walk), array members follow their nodes, and :func:`_skops_pack` fixes the
    rest."""
    import skops.io as sio

    schema, members = _skops_open(sio.dumps(estimator), "a fitted estimator")
    ids: dict[int, int] = {}
    files: dict[str, str] = {}

    def walk(node):
        if isinstance(node, list):
            for v in node:
                walk(v)
        elif isinstance(node, dict):
            for k, v in node.items():
                if k == "__id__" and isinstance(v, int):
                    node[k] = ids.setdefault(v, len(ids))
                elif k == "file" and isinstance(v, str) and v in members:
                    node[k] = files.setdefault(v, f"a{len(files)}.npy")
                else:
                    walk(v)

    walk(schema)
    renamed = {files.get(name, name): data for name, data in members.items()}
    return _skops_pack(schema, renamed)


def load_estimator(blob: bytes, where: str, trusted: list[str]):
    """skops.io load that refuses, in one sentence, any type outside the trusted list.

    skops rebuilds objects from a declarative description and only instantiates types it
    is told to trust, so opening a model file never runs code from the file.
    """
    import skops.io as sio

    allowed = set(trusted)
    try:
        untrusted = sio.get_untrusted_types(data=blob)
    except Exception:
        raise AffordError(f"{where} is not a readable estimator") from None
    refused = [t for t in untrusted if t not in allowed]
    if refused:
        raise AffordError(f"{where} holds the untrusted type {refused[0]}; refusing to load it")
    try:
        return sio.loads(blob, trusted=untrusted)
    except Exception as exc:
        raise AffordError(f"{where} cannot be loaded ({type(exc).__name__})") from None


def artifact_bytes(kind: str, arrays: dict[str, np.ndarray], meta: dict[str, Any], *,
                   parents: list[dict[str, str]] | None = None, seed: int | None = None,
                   blobs: dict[str, bytes] | None = None, command: list[str] | None = None) -> bytes:
    """Serialise an artefact to zip bytes (array members are byte-stable for equal arrays)."""
    if kind not in KINDS:
        raise ValueError(f"unknown artefact kind {kind!r}")
    members: dict[str, bytes] = {}
    for name, arr in sorted(arrays.items()):
        if arr.dtype == object:
            raise ValueError(f"array {name!r} has dtype object; artefacts hold plain arrays only")
        members[f"{name}.npy"] = _npy_bytes(arr)
    for name, blob in sorted((blobs or {}).items()):
        members[f"{name}.skops"] = blob
    manifest = {
        "format": FORMAT,
        "kind": kind,
        "schema_version": SCHEMA_VERSION,
        "afford_version": _version(),
        "created": _created(),
        "command": list(sys.argv if command is None else command),
        "seed": seed,
        "parents": list(parents or []),
        "members": {name: _sha256(data) for name, data in members.items()},
        **meta,
    }
    text = json.dumps(manifest, indent=1, sort_keys=True).encode()
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as zf:
        for name, data in [("manifest.json", text), (_SEAL, _sha256(text).encode())] + list(members.items()):
            info = zipfile.ZipInfo(name, date_time=_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            zf.writestr(info, data)
    return buf.getvalue()


def _target(path: str) -> tuple[str, Path]:
    """Where output ``path`` goes, decided before any work (DESIGN.md section 3):

    * ``("stream", p)``: a character device, FIFO or socket (``/dev/null``, ``/dev/stdout``
      onto a pipe, ``/dev/fd/N`` from a shell's ``>(cmd)``): written in order, never replaced;
    * ``("file", p)``: a regular file, or none yet: written beside itself and renamed into
      place, atomically. A symlink is followed: its target is written, the link stays.

    A name ending in ``/``, a directory, a missing parent and a place that takes no new file
    are refused in one sentence naming the target.
    """
    if not path:
        raise AffordError("give a file name for the output (-o FILE, or -o - for stdout)")
    if path.endswith("/") or path.endswith(os.sep):
        raise AffordError(f"{path} ends in '/': give a file name, not a directory")
    p = Path(path)
    if p.is_dir():
        raise AffordError(f"{path} is a directory; give a file name")
    try:
        mode = os.stat(p).st_mode  # follows symlinks
    except FileNotFoundError:
        mode = None
    except OSError as exc:
        raise AffordError(f"cannot write {path}: {exc.strerror.lower() if exc.strerror else exc}") from None
    if mode is not None and (not stat.S_ISREG(mode) or _is_fd_path(p)):
        if not os.access(p, os.W_OK):
            raise AffordError(f"cannot write {path}: permission denied")
        return "stream", p
    real = Path(os.path.realpath(p))  # a link's target; a dangling link's would-be target
    parent = real.parent
    if not parent.is_dir():
        raise AffordError(f"cannot write {path}: the directory {parent} does not exist")
    if mode is not None and not os.access(real, os.W_OK):
        raise AffordError(f"cannot write {path}: permission denied")
    try:  # the only sure test of "can a new file go here" (/proc, /sys and read-only mounts say yes to access())
        with uninterrupted():  # an interruption between making the probe and removing it left it behind
            fd, probe = tempfile.mkstemp(prefix=f".{real.name}.", suffix=".probe", dir=parent)
            os.close(fd)
            os.unlink(probe)
    except OSError as exc:
        reason = exc.strerror.lower() if exc.strerror else "it takes no new file"
        raise AffordError(f"cannot write {path}: {parent} refuses new files ({reason})") from None
    return "file", real


def _is_fd_path(p: Path) -> bool:
    """``/dev/stdout``, ``/dev/fd/N``, ``/proc/self/fd/N``: an open descriptor, written in
    place even when it is a regular file (a shell's ``> file``), never renamed over."""
    text = os.path.abspath(p)
    return text in ("/dev/stdout", "/dev/stderr") or bool(re.match(r"^/(dev/fd|proc/(self|\d+)/fd)/\d+$", text))


def writes_stdout(path: str) -> bool:
    """Does output ``path`` land on this process's standard output (``-``, ``/dev/stdout``,
    a pipe or file stdout also holds)? Then the report goes to stderr."""
    if path == "-":
        return True
    try:
        here, there = os.fstat(sys.stdout.fileno()), os.stat(path)
    except (OSError, ValueError, AttributeError):
        return False
    return (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)


def output_is_file(path: str) -> bool:
    """Is output ``path`` a file written atomically (not stdout, a device or a pipe)? Then
    work may keep a journal beside it."""
    return path != "-" and not writes_stdout(path) and _target(path)[0] == "file"


def _same_file(a: str, b: str) -> bool:
    """Are output ``a`` and input ``b`` one existing file (a link, ``./x`` or a hard link to
    it too)? Input ``-`` is standard input: the same file when a shell redirected it from ``a``."""
    if a == "-" or not a or not b:
        return False
    if b == "-":
        try:
            here, there = os.fstat(sys.stdin.fileno()), os.stat(a)
        except (OSError, ValueError, AttributeError):
            return False
        return stat.S_ISREG(here.st_mode) and (here.st_dev, here.st_ino) == (there.st_dev, there.st_ino)
    try:
        return os.path.samefile(a, b)
    except (OSError, ValueError):
        return os.path.realpath(a) == os.path.realpath(b)


def check_not_input(path: str, inputs=()) -> None:
    """Refuse output ``path`` when it is one of the command's ``inputs``: writing it would
    destroy what is being read (checked before any work)."""
    for source in inputs or ():
        if _same_file(path, str(source)):
            raise AffordError(f"{path} is an input of this command; give another output path")


def check_output(path: str, inputs=()) -> None:
    """Fail before any work if ``path`` cannot take the output (``-`` always can, unless it
    is a terminal and the output is an artefact), or if it is one of ``inputs``, the paths
    the command reads."""
    check_not_input(path, inputs)
    if path == "-" or writes_stdout(path):
        if sys.stdout.isatty():
            raise AffordError("refusing to write an artefact to the terminal; give -o FILE or pipe it on")
        if path == "-":
            return
    _target(path)


def write_artifact(path: str, data: bytes) -> None:
    """Write ``data`` to ``path`` (see :func:`_target`): stdout for ``-``, streamed to a device
    or pipe, else atomically (a temporary file beside the target, renamed into place)."""
    if path == "-":
        out = sys.stdout.buffer
        out.write(data)
        out.flush()
        return
    kind, target = _target(path)
    if kind == "stream":
        try:
            with open(target, "wb", buffering=0) as fh:
                fh.write(data)
        except OSError as exc:
            raise AffordError(f"cannot write {path}: {exc.strerror.lower() if exc.strerror else exc}") from None
        return
    tmp = None
    try:
        with uninterrupted():  # the temporary file exists only once its clean-up below is armed
            fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
            umask = os.umask(0)
            os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)  # mkstemp makes 0600; a saved artefact gets the usual mode
        with os.fdopen(fd, "wb") as fh:
            fh.write(data)
            fh.flush()
            os.fsync(fh.fileno())
        os.replace(tmp, target)
    except BaseException:
        if tmp is not None:
            try:
                os.unlink(tmp)
            except FileNotFoundError:
                pass
        raise


def _read_source(path: str) -> bytes:
    if path == "-":
        if sys.stdin.isatty():
            raise AffordError("no artefact on standard input (pipe one in, or give a file name)")
        return sys.stdin.buffer.read()
    p = Path(path)
    if not p.exists():
        raise AffordError(f"{path} does not exist")
    if p.is_dir():
        raise AffordError(f"{path} is a directory, not an afford file")
    return p.read_bytes()


def _migrate(manifest: dict) -> dict:
    """Bring an older manifest up to SCHEMA_VERSION. 1 -> 2 added only the manifest's own
    checksum member, which :func:`read_artifact` asks of schema 2 files alone."""
    return manifest


def read_artifact(path: str, kinds: tuple[str, ...] | str | None = None, *, data: bytes | None = None) -> Artifact:
    """Read and verify an artefact; ``kinds`` lists what the caller accepts."""
    name = "standard input" if path == "-" else path
    raw = _read_source(path) if data is None else data
    if not raw:
        raise AffordError(f"{name} is empty, not an afford file")
    try:
        zf = zipfile.ZipFile(io.BytesIO(raw))
        text = zf.read("manifest.json")
        manifest = json.loads(text)
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError, UnicodeDecodeError, ValueError):
        raise AffordError(f"{name} is not an afford file") from None
    except (NotImplementedError, OSError, EOFError, RuntimeError):  # unsupported compression, bad directory
        raise AffordError(f"{name} is corrupt: its zip structure cannot be read") from None
    if not isinstance(manifest, dict) or manifest.get("format") != FORMAT:
        raise AffordError(f"{name} is not an afford file")
    kind = manifest.get("kind")
    if kind not in KINDS:
        raise AffordError(f"{name} is of an unknown artefact kind {kind!r}; it is corrupt or was edited")
    version = manifest.get("schema_version")
    if not isinstance(version, int):
        raise AffordError(f"{name} has no valid schema_version; it is corrupt or was edited")
    if version > SCHEMA_VERSION:
        raise AffordError(f"{name} was written with artefact schema {version}, newer than this afford "
                          f"understands ({SCHEMA_VERSION}); upgrade afford")
    if version < MIN_SCHEMA_VERSION:
        raise AffordError(f"{name} uses artefact schema {version}, which this afford can no longer read "
                          f"(oldest supported: {MIN_SCHEMA_VERSION}); re-create it")
    if version >= 2:
        try:
            seal = zf.read(_SEAL).decode("ascii")
        except (KeyError, zipfile.BadZipFile, OSError, EOFError, UnicodeDecodeError, NotImplementedError):
            raise AffordError(f"{name} is corrupt or was edited: its manifest checksum is missing") from None
        if seal != _sha256(text):
            raise AffordError(f"{name} is corrupt or was edited: manifest.json does not match its checksum")
    else:
        later = sorted(set(manifest) & _LATER_FIELDS)
        if later or _SEAL in zf.namelist():
            raise AffordError(f"{name} claims artefact schema 1 but carries what only later schemas write "
                              f"({(later or [_SEAL])[0]}); it was edited")
    manifest = _migrate(manifest)
    if kinds is not None:
        wanted = (kinds,) if isinstance(kinds, str) else tuple(kinds)
        if kind not in wanted:
            raise AffordError(f"{name} is an artefact of kind {kind!r}, but this command needs {' or '.join(repr(k) for k in wanted)}")
    members = manifest.get("members")
    if not isinstance(members, dict):
        raise AffordError(f"{name} lists no members; it is corrupt or was edited")
    present = set(zf.namelist()) - {"manifest.json", _SEAL}
    if present != set(members):
        extra = sorted(present - set(members)) or sorted(set(members) - present)
        raise AffordError(f"{name} is corrupt or was edited: member {extra[0]} does not match the manifest")
    arrays: dict[str, np.ndarray] = {}
    blobs: dict[str, bytes] = {}
    for member, digest in sorted(members.items()):
        try:
            blob = zf.read(member)
        except (zipfile.BadZipFile, OSError, EOFError, NotImplementedError):  # zlib errors: BadZipFile
            raise AffordError(f"{name} is corrupt: member {member} cannot be read") from None
        except Exception:
            raise AffordError(f"{name} is corrupt: member {member} cannot be read") from None
        if _sha256(blob) != digest:
            raise AffordError(f"{name} is corrupt or was edited: checksum mismatch in {member}")
        if member.endswith(".npy"):
            arrays[member[:-4]] = _load_npy(blob, f"{name}: member {member}")
        elif member.endswith(".skops"):
            blobs[member[:-6]] = blob
        else:
            raise AffordError(f"{name} holds an unknown member {member}")
    return Artifact(kind=kind, manifest=manifest, arrays=arrays, blobs=blobs, sha256=_sha256(raw), source=name,
                    sealed=version >= 2)


#: Manifest fields that schema 1 files never had: a file claiming schema 1 with one of them
#: was relabelled (to skip the manifest's own checksum).
_LATER_FIELDS = {"label_source", "result_names", "n_entities"}


def _load_npy(blob: bytes, where: str) -> np.ndarray:
    """An npy member, its header checked before anything is allocated: a plain numeric or
    boolean dtype, and no more elements than the member's bytes can hold."""
    buf = io.BytesIO(blob)
    try:
        major, _ = np.lib.format.read_magic(buf)
        read = np.lib.format.read_array_header_1_0 if major == 1 else np.lib.format.read_array_header_2_0
        shape, _, dtype = read(buf)
    except (ValueError, OSError, EOFError, TypeError, SyntaxError):
        raise AffordError(f"{where} is not a readable array") from None
    if dtype.hasobject:
        raise AffordError(f"{where} is an array that needs pickle; refused")
    if dtype.kind not in "biuf":
        raise AffordError(f"{where} holds {dtype} values, not numbers; it was edited")
    count = int(np.prod(shape, dtype=object))
    if count * dtype.itemsize > len(blob) - buf.tell():
        raise AffordError(f"{where} claims {count} values ({'x'.join(map(str, shape))}) but holds "
                          f"{len(blob) - buf.tell()} bytes; it is corrupt or was edited")
    try:
        return np.load(io.BytesIO(blob), allow_pickle=False)
    except (ValueError, OSError, EOFError):
        raise AffordError(f"{where} is not a readable array") from None
