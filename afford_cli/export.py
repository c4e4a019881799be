"""Interactions as a table: a pandas DataFrame, CSV or Parquet (``afford export``).

One row per interaction. The columns, in order:

* ``episode``, ``step``, ``behavior`` (its name), ``alpha.<parameter>`` per parameter any
  behaviour takes (empty where this row's behaviour has none);
* the entity the robot perceived before acting, one column per feature, named as the
  schema names it (``visibility``, ``x``, ... or ``range_min.l0.r0.c0``, ...);
* the entity it perceived after, ``after.<feature>`` per feature, where the interactions
  record one (not where the labels were given instead): the effect is after minus before;
* ``result`` (the robot's own reading, by name) where the labels were given;
  ``category`` (the discovered effect category, -1 for rows pruned as rare) for an effects
  or features artefact;
* ``truth.<name>`` (``truth.<name>.<i>`` for each column of a multi-column one): what the
  simulator knew and the robot did not, for reports only (outcomes and shapes by name).

pandas is an optional extra (``pip install 'afford[export]'``), and Parquet needs pyarrow too
(``afford[parquet]``); without them the export refuses in one sentence.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from afford.errors import AffordError
from afford.learning import read_effects, read_rows

__all__ = ["FORMATS", "to_frame", "frame_of", "export_bytes", "format_for", "check_extras"]

FORMATS = ("csv", "parquet")
_EXTRA = {"pandas": "export", "pyarrow": "parquet"}


def _need(module: str, what: str):
    try:
        return __import__(module)
    except ImportError:
        raise AffordError(f"{what} needs {module}, an optional extra: pip install 'afford[{_EXTRA[module]}]'") from None


def frame_of(data, labels: np.ndarray | None = None):
    """The DataFrame of :class:`Interactions` ``data`` (``labels``: discovered categories)."""
    pd = _need("pandas", "a DataFrame of interactions")
    n = len(data)
    columns: dict[str, np.ndarray] = {
        "episode": np.asarray(data.episode),
        "step": np.asarray(data.step),
        "behavior": np.asarray(data.behavior_names, dtype=object)[np.asarray(data.behavior, dtype=int)],
    }
    names: list[str] = []
    for spec in data.behaviors:
        for p in spec.get("parameters", []):
            if p["name"] not in names:
                names.append(p["name"])
    for j, pname in enumerate(names):
        col = np.full(n, np.nan)
        for b, spec in enumerate(data.behaviors):
            own = [p["name"] for p in spec.get("parameters", [])]
            if pname in own:
                rows = data.behavior == b
                col[rows] = data.params[rows, own.index(pname)]
        columns[f"alpha.{pname}"] = col
    before = data.before
    frame = pd.DataFrame(columns)
    feats = pd.DataFrame(before, columns=list(data.schema.names))
    parts = [frame, feats]
    if data.has_after:
        parts.append(pd.DataFrame(data.after, columns=[f"after.{name}" for name in data.schema.names]))
    extra: dict[str, np.ndarray] = {}
    if data.result is not None:
        extra["result"] = np.asarray(data.result_names, dtype=object)[np.asarray(data.result, dtype=int)]
    if labels is not None:
        extra["category"] = np.asarray(labels, dtype=np.int16)
    for key in sorted(data.truth):
        arr = np.asarray(data.truth[key])
        named = {"outcome": list(data.outcome_names), "shape": list(data.shapes)}.get(key)
        if named and arr.ndim == 1 and arr.size and 0 <= arr.min() and arr.max() < len(named):
            extra[f"truth.{key}"] = np.asarray(named, dtype=object)[arr.astype(int)]  # by name
        elif arr.ndim == 1:
            extra[f"truth.{key}"] = arr
        else:
            for i in range(arr.reshape(n, -1).shape[1]):
                extra[f"truth.{key}.{i}"] = arr.reshape(n, -1)[:, i]
    if extra:
        parts.append(pd.DataFrame(extra))
    return pd.concat(parts, axis=1)


def to_frame(path: str):
    """The DataFrame of an interactions, effects or features artefact (see the module)."""
    art, data = read_rows(path)
    labels = read_effects(art, data)[0] if "category" in art.arrays else None
    return frame_of(data, labels)


def format_for(output: str, given: str | None) -> str:
    """The format asked for, else the output's suffix (``.csv``, ``.parquet``), else csv."""
    if given is not None:
        fmt = given.lower()
        if fmt not in FORMATS:
            raise AffordError(f"afford cannot export to {given!r}; the formats are {' and '.join(FORMATS)}")
        return fmt
    suffix = Path(output).suffix.lower().lstrip(".")
    return suffix if suffix in FORMATS else "csv"


def check_extras(fmt: str) -> None:
    """Refuse, before any work, an export whose optional extra is not installed."""
    _need("pandas", f"exporting to {fmt}")
    if fmt == "parquet":
        _need("pyarrow", "exporting to parquet")


def export_bytes(frame, fmt: str) -> bytes:
    """``frame`` serialised as ``fmt``."""
    if fmt == "csv":
        return frame.to_csv(index=False).encode()
    _need("pyarrow", "exporting to parquet")
    buf = io.BytesIO()
    frame.to_parquet(buf, index=False)
    return buf.getvalue()
