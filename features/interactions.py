"""Relation instances <f^(), b(alpha), f^(b)>: what exploration records.

An :class:`Interactions` holds, row by row, the perceived object before and after a
behaviour, which behaviour ran with which parameters, and, kept apart under ``truth``,
what physically happened (for reports and evaluation only; learning never reads it).
It lives in ``features`` because both the simulator that writes it and the learner that
reads it may import only this package.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from afford.features.errors import DataError
from afford.features.schema import FeatureSchema

__all__ = ["Interactions", "OUTCOMES", "encode_parameters"]

#: Ground-truth outcome labels, the first that applies (issue: fell, left-view, lifted,
#: dragged, no-change).
OUTCOMES = ("fell", "left-view", "lifted", "dragged", "no-change")


def encode_parameters(values: np.ndarray, parameters: list[dict]) -> np.ndarray:
    """Behaviour parameters alpha as a learner sees them: a periodic one (an angle in
    degrees) as its sine and cosine, so that 359 and 1 degrees lie close; others as they are.

    ``values`` is (n, p) or (p,), with at least ``len(parameters)`` columns.
    """
    values = np.asarray(values, dtype=float)
    one = values.ndim == 1
    v = values[None, :] if one else values
    cols = []
    for j, p in enumerate(parameters):
        if p.get("periodic"):
            angle = np.radians(v[:, j])
            cols += [np.sin(angle), np.cos(angle)]
        else:
            cols.append(v[:, j])
    out = np.column_stack(cols) if cols else np.zeros((v.shape[0], 0))
    return out[0] if one else out


@dataclass
class Interactions:
    """Relation instances <effect or result, entity, behaviour(alpha)>, ground truth apart.

    Entities are stored once each (``entities``, float32) and rows point into that table:
    an environment scanned once and tried with seven behaviours (Algorithm 1) is one
    entity and seven rows; an object played with until it stops changing (Algorithm 5)
    is one entity per look, each row's ``after`` the next row's ``before``.

    A row's label comes from one of two sources:

    - ``discovered``: the effect ``after - before`` is clustered into categories
      (``afford cluster``); such rows have an after-entity;
    - ``given``: the robot's own reading of whether the behaviour succeeded (``result``,
      from its own sensors, e.g. odometry in chapter 5), stored apart from ground truth.
      Such rows may have no after-entity (chapter 5's robot does not look again).

    Attributes
    ----------
    schema : FeatureSchema
    behaviors : list of dict
        ``{"name", "parameters": [{"name", "low", "high", "unit", "periodic"}], "target",
        "description"}``.
    entities : (m, d) float array
        Every perceived entity once.
    before_index : (n,) int array
        Row -> the entity before the behaviour.
    after_index : (n,) int array or None
        Row -> the entity after it (None: nothing is perceived after behaviours).
    behavior : (n,) int array, index into ``behaviors``
    params : (n, p) float array, the behaviour parameters alpha (p = most any behaviour takes)
    episode, step : (n,) int arrays
    result : (n,) int array or None
        Given labels: the index into ``result_names`` of the robot's own reading.
    result_names : list of str
        E.g. ``["fail", "success"]``.
    truth : dict of (n, ...) arrays
        What physically happened, for reports and evaluation only.
    shapes : list of str
    scene : dict, the scene's configuration
    outcome_names : list of str
        What ``truth["outcome"]`` indexes (the scene's outcomes; the table's by default).
    """

    schema: FeatureSchema
    behaviors: list[dict]
    entities: np.ndarray
    before_index: np.ndarray
    after_index: np.ndarray | None
    behavior: np.ndarray
    params: np.ndarray
    episode: np.ndarray
    step: np.ndarray
    result: np.ndarray | None = None
    result_names: list[str] = field(default_factory=list)
    truth: dict[str, np.ndarray] = field(default_factory=dict)
    shapes: list[str] = field(default_factory=list)
    scene: dict = field(default_factory=dict)
    outcome_names: list[str] = field(default_factory=lambda: list(OUTCOMES))

    #: Per-row arrays (always present).
    ARRAYS = ("before_index", "behavior", "params", "episode", "step")

    @classmethod
    def from_rows(cls, schema: FeatureSchema, behaviors: list[dict], before: np.ndarray, after: np.ndarray | None,
                  behavior: np.ndarray, params: np.ndarray, episode: np.ndarray, step: np.ndarray,
                  **rest) -> "Interactions":
        """Interactions from one before (and after) vector per row, each stored as its own entity."""
        before = np.asarray(before)
        n = before.shape[0]
        if after is None:
            entities, after_index = before, None
        else:
            entities = np.concatenate([before, np.asarray(after)])
            after_index = np.arange(n, 2 * n, dtype=np.int32)
        return cls(schema=schema, behaviors=behaviors, entities=entities, before_index=np.arange(n, dtype=np.int32),
                   after_index=after_index, behavior=np.asarray(behavior), params=np.asarray(params),
                   episode=np.asarray(episode), step=np.asarray(step), **rest)

    def __len__(self) -> int:
        return int(self.before_index.shape[0])

    @property
    def behavior_names(self) -> list[str]:
        return [b["name"] for b in self.behaviors]

    @property
    def label_source(self) -> str:
        """``given`` (the robot's own success reading) or ``discovered`` (effects to cluster)."""
        return "given" if self.result is not None else "discovered"

    @property
    def has_after(self) -> bool:
        return self.after_index is not None

    @property
    def before(self) -> np.ndarray:
        """f^() per row, (n, d)."""
        return self.entities[self.before_index]

    @property
    def after(self) -> np.ndarray:
        """f^(b) per row, (n, d)."""
        if self.after_index is None:
            raise DataError("these interactions record no entity after the behaviours (their labels are given), "
                             "so they have no effects")
        return self.entities[self.after_index]

    def before_rows(self, rows: np.ndarray) -> np.ndarray:
        """f^() of some rows (cheaper than ``before[rows]``, which builds every row)."""
        return self.entities[self.before_index[rows]]

    def effects_of(self, rows: np.ndarray) -> np.ndarray:
        """f^(b) - f^() of some rows."""
        if self.after_index is None:
            self.after  # raises the one-sentence error
        return self.entities[self.after_index[rows]].astype(np.float64) - self.entities[self.before_index[rows]]

    @property
    def effects(self) -> np.ndarray:
        """f_effect = f^(b) - f^() per row."""
        return self.after.astype(np.float64) - self.before

    def validate(self) -> None:
        """Raise ValueError with one sentence if the arrays do not fit together."""
        n = len(self)
        d = len(self.schema)
        if self.entities.ndim != 2 or self.entities.shape[1] != d:
            raise DataError(f"interactions have {self.entities.shape[-1]} features but the schema names {d}")
        if self.entities.dtype.kind != "f":
            raise DataError("the interactions' entity features are not numbers")
        m = self.entities.shape[0]
        for name in self.ARRAYS + (("after_index",) if self.after_index is not None else ()) + (
                ("result",) if self.result is not None else ()):
            arr = getattr(self, name)
            if arr.ndim < 1 or arr.shape[0] != n:
                raise DataError(f"interactions array {name!r} has {arr.shape[0] if arr.ndim else 0} rows, expected {n}")
            if arr.dtype.kind not in "iuf" or (name != "params" and arr.dtype.kind == "f"):
                raise DataError(f"interactions array {name!r} does not hold integers")
        for name in ("before_index", "after_index"):
            idx = getattr(self, name)
            if idx is not None and n and (idx.min() < 0 or idx.max() >= m):
                raise DataError(f"interactions array {name!r} points outside the {m} stored entities")
        if self.params.ndim != 2:
            raise DataError("interactions array 'params' must be a table (rows x parameters)")
        for name, arr in self.truth.items():
            if arr.ndim < 1 or arr.shape[0] != n:
                raise DataError(f"ground-truth array {name!r} has the wrong number of rows, expected {n}")
        if n and (self.behavior.min() < 0 or self.behavior.max() >= len(self.behaviors)):
            raise DataError("an interaction names a behaviour the file does not list")
        if self.result is not None and n and (self.result.min() < 0 or self.result.max() >= len(self.result_names)):
            raise DataError("an interaction's result is not one of the results the file lists")
        if not np.isfinite(self.entities).all():
            raise DataError("the interactions hold NaN or infinite features")

    def subset(self, rows: np.ndarray) -> "Interactions":
        """These rows only (the entity table is shared, not copied)."""
        rows = np.asarray(rows)
        return Interactions(
            schema=self.schema, behaviors=self.behaviors, entities=self.entities,
            **{k: getattr(self, k)[rows] for k in self.ARRAYS},
            after_index=None if self.after_index is None else self.after_index[rows],
            result=None if self.result is None else self.result[rows], result_names=self.result_names,
            truth={k: v[rows] for k, v in self.truth.items()},
            shapes=self.shapes, scene=self.scene, outcome_names=self.outcome_names,
        )

    def compact(self) -> "Interactions":
        """The same rows with only the entities they point to, in order of first use."""
        used = [self.before_index] + ([self.after_index] if self.after_index is not None else [])
        keep = np.unique(np.concatenate(used)) if len(self) else np.zeros(0, dtype=np.int64)
        if keep.size == self.entities.shape[0]:
            return self
        new = np.full(self.entities.shape[0], -1, dtype=np.int32)
        new[keep] = np.arange(keep.size, dtype=np.int32)
        out = self.subset(np.arange(len(self)))
        out.entities = self.entities[keep]
        out.before_index = new[self.before_index]
        if self.after_index is not None:
            out.after_index = new[self.after_index]
        return out

    @classmethod
    def concatenate(cls, parts: list["Interactions"]) -> "Interactions":
        first = parts[0]
        offsets = np.cumsum([0] + [p.entities.shape[0] for p in parts[:-1]])
        shift = lambda name: np.concatenate([getattr(p, name) + o for p, o in zip(parts, offsets)]).astype(np.int32)
        return cls(
            schema=first.schema, behaviors=first.behaviors,
            entities=np.concatenate([p.entities for p in parts]),
            before_index=shift("before_index"),
            after_index=None if first.after_index is None else shift("after_index"),
            **{k: np.concatenate([getattr(p, k) for p in parts]) for k in cls.ARRAYS if k != "before_index"},
            result=None if first.result is None else np.concatenate([p.result for p in parts]),
            result_names=first.result_names,
            truth={k: np.concatenate([p.truth[k] for p in parts]) for k in first.truth},
            shapes=first.shapes, scene=first.scene, outcome_names=first.outcome_names,
        )
