"""The exploration journal: finished episodes kept beside the output as they arrive.

``afford explore -o OUT`` writes each finished episode to ``OUT.partial/`` at once, so a
Ctrl-C, a SIGTERM or a ``kill -9`` loses only the episodes still running; ``--resume``
runs the rest and writes the same bytes an uninterrupted run would have (each episode is
drawn from its own generator, seeded by (seed, episode)). Once the output is written whole
the journal is removed. The folder holds::

    identity.json   what decides the rows: scene settings, seed, episode range or
                    interaction count, most steps (not --workers or --backend)
    meta.json       what every episode's rows share (schema, behaviours, scene)
    episodes.log    one record per finished episode, appended:
                    b"AFJ1", episode (u32), length (u64), CRC-32 (u32), then an
                    uncompressed .npz of the episode's arrays (read with allow_pickle=False)

A record is flushed as soon as it is written (a killed process loses nothing the kernel
has) and the file is synced every few seconds. Reading stops at the first record that is
cut short or fails its checksum: that is where a killed run was writing, and what follows
is dropped before appending.
"""

from __future__ import annotations

import io
import json
import os
import shutil
import struct
import time
import zlib
from pathlib import Path

import numpy as np

from afford.artifacts import Artifact
from afford.datasets import explored_settings, interactions_from_artifact, interactions_members, settings_difference
from afford.errors import AffordError

__all__ = ["Journal", "journal_path"]

_MAGIC = b"AFJ1"
_HEAD = struct.Struct("<4sIQI")
_STATIC = ("schema", "behaviors", "scene", "shapes", "result_names", "outcome_labels", "label_source")
_SYNC_EVERY = 5.0


def journal_path(output: str) -> Path:
    return Path(output + ".partial")


def _canonical(value) -> str:
    return json.dumps(value, sort_keys=True, default=str)


class Journal:
    """Episodes of one exploration, appended as they finish (see the module docstring)."""

    def __init__(self, directory: Path, identity: dict):
        self.dir = Path(directory)
        self.identity = identity
        self.kept: dict[int, object] = {}
        self._log = None
        self._meta: dict | None = None
        self._synced = time.monotonic()
        self.created = False  # this run made the journal (it did not resume one)

    # -- opening ------------------------------------------------------------------------
    @classmethod
    def start(cls, directory: Path, identity: dict, resume: bool) -> "Journal":
        """The journal for a run: a new one, or (``resume``) the one left by an interrupted
        run of the same exploration, with its finished episodes read back in ``kept``."""
        journal = cls(directory, identity)
        d = journal.dir
        if d.exists() and not d.is_dir():
            raise AffordError(f"{d} is in the way of the exploration's journal: it is not a folder")
        if d.exists():
            if not resume:
                n = journal.count()
                raise AffordError(f"{d} holds {n} finished episode{'s' * (n != 1)} of an interrupted exploration: "
                                  "give --resume to finish it, or remove that folder to start afresh")
            journal._open_existing()
        else:
            journal._create()
        return journal

    def _create(self) -> None:
        tmp = self.dir.with_name(self.dir.name + f".tmp{os.getpid()}")
        shutil.rmtree(tmp, ignore_errors=True)
        tmp.mkdir()
        (tmp / "identity.json").write_text(_canonical(self.identity))
        (tmp / "episodes.log").touch()
        os.replace(tmp, self.dir)  # the journal appears whole, or not at all
        self.created = True
        self._log = self._locked(open(self.dir / "episodes.log", "ab"))

    def _open_existing(self) -> None:
        try:
            stored = json.loads((self.dir / "identity.json").read_text())
        except (OSError, ValueError):
            raise AffordError(f"{self.dir} is not an exploration journal afford can read (no readable identity.json); "
                              "remove it to start afresh") from None
        mine = json.loads(_canonical(self.identity))
        if isinstance(stored, dict) and isinstance(stored.get("scene"), dict):
            # journals written before the identity left them out still hold the learner defaults
            stored["scene"] = explored_settings(stored["scene"])
        if stored != mine:
            key = next(k for k in sorted(set(stored) | set(mine), key=lambda k: (k == "scene", k))
                       if stored.get(k) != mine.get(k))
            why = (f"its scene settings differ: {settings_difference(stored.get(key) or {}, mine.get(key) or {})}"
                   if key == "scene" else f"its {key.replace('_', ' ')} is {stored.get(key)}, this run's {mine.get(key)}")
            raise AffordError(f"{self.dir} is the journal of another exploration ({why}): give that run's "
                              "options to resume it, or remove the folder to start afresh")
        meta = self.dir / "meta.json"
        if meta.exists():
            try:
                self._meta = json.loads(meta.read_text())
            except (OSError, ValueError):
                raise AffordError(f"{meta} is unreadable; remove {self.dir} to start afresh") from None
        log = self._locked(open(self.dir / "episodes.log", "ab"))  # before reading: no one else appends
        end = self._read()
        log.truncate(end)  # drop a record a killed run left half-written
        self._log = log

    def _locked(self, f):
        """``f``, locked for this process alone: two runs never append to one journal."""
        try:
            import fcntl
        except ImportError:  # pragma: no cover - not POSIX: no lock
            return f
        try:
            fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            f.close()
            raise AffordError(f"another afford explore is writing {self.dir}; wait for it, or stop it first") from None
        return f

    # -- reading ------------------------------------------------------------------------
    def _records(self):
        """``(episode, payload, end offset)`` of each whole record, in order."""
        path = self.dir / "episodes.log"
        if not path.exists():
            return
        with open(path, "rb") as f:
            offset = 0
            while True:
                head = f.read(_HEAD.size)
                if len(head) < _HEAD.size:
                    return
                magic, episode, length, crc = _HEAD.unpack(head)
                if magic != _MAGIC:
                    return
                payload = f.read(length)
                if len(payload) < length or zlib.crc32(payload) != crc:
                    return
                offset += _HEAD.size + length
                yield episode, payload, offset

    def count(self) -> int:
        """Finished episodes whole on disk (a record a write was cut short in is not one)."""
        return len({e for e, _, _ in self._records()})

    def _read(self) -> int:
        end = 0
        for episode, payload, end in self._records():
            if episode in self.kept or self._meta is None:
                continue
            try:
                with np.load(io.BytesIO(payload), allow_pickle=False) as z:
                    arrays = {k: z[k] for k in z.files}
            except (ValueError, OSError, zlib.error) as exc:
                raise AffordError(f"{self.dir}: episode {episode}'s record is unreadable ({exc}); "
                                  "remove the folder to start afresh") from None
            art = Artifact(kind="interactions", manifest=self._meta, arrays=arrays,
                           source=f"{self.dir} (episode {episode})")
            self.kept[episode] = interactions_from_artifact(art)
        return end

    # -- writing ------------------------------------------------------------------------
    def append(self, pairs) -> None:
        """Record newly finished ``(episode, rows)`` pairs, each flushed at once."""
        for episode, data in pairs:
            arrays, meta = interactions_members(data)
            if self._meta is None:
                self._meta = {k: meta[k] for k in _STATIC if k in meta}
                tmp = self.dir / "meta.json.tmp"
                tmp.write_text(_canonical(self._meta))
                os.replace(tmp, self.dir / "meta.json")
            buf = io.BytesIO()
            np.savez(buf, **arrays)
            payload = buf.getvalue()
            self._log.write(_HEAD.pack(_MAGIC, episode, len(payload), zlib.crc32(payload)) + payload)
            self._log.flush()
            self.kept[episode] = data
        if time.monotonic() - self._synced > _SYNC_EVERY:
            os.fsync(self._log.fileno())
            self._synced = time.monotonic()

    def close(self) -> None:
        if self._log is not None:
            log, self._log = self._log, None
            try:
                log.flush()
                os.fsync(log.fileno())
            finally:
                log.close()

    def remove(self) -> None:
        """The output is written whole: the journal has done its work."""
        self.close()
        shutil.rmtree(self.dir, ignore_errors=True)
