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

from features.schema import FeatureSchema

__all__ = ["Interactions", "OUTCOMES"]

#: Ground-truth outcome labels, the first that applies (issue: fell, left-view, lifted,
#: dragged, no-change).
OUTCOMES = ("fell", "left-view", "lifted", "dragged", "no-change")


@dataclass
class Interactions:
    """Rows of (before, behaviour, alpha, after) with ground truth kept apart.

    Attributes
    ----------
    schema : FeatureSchema
    behaviors : list of dict
        ``{"name", "parameters": [{"name", "low", "high", "unit"}], "description"}``.
    before, after : (n, d) float arrays
    behavior : (n,) int array, index into ``behaviors``
    params : (n, p) float array, the behaviour parameters alpha (p = most any behaviour takes)
    episode, step : (n,) int arrays
    truth : dict of (n, ...) arrays
        ``shape`` (index into ``shapes``), ``size`` (n, 3, NaN-padded), ``pose_before`` and
        ``pose_after`` (n, 7: x y z qw qx qy qz), ``in_hand_before``, ``in_hand_after``,
        ``reachable``, ``contact``, ``outcome`` (index into :data:`OUTCOMES`).
    shapes : list of str
    scene : dict, the scene's configuration
    """

    schema: FeatureSchema
    behaviors: list[dict]
    before: np.ndarray
    after: np.ndarray
    behavior: np.ndarray
    params: np.ndarray
    episode: np.ndarray
    step: np.ndarray
    truth: dict[str, np.ndarray] = field(default_factory=dict)
    shapes: list[str] = field(default_factory=list)
    scene: dict = field(default_factory=dict)

    ARRAYS = ("before", "after", "behavior", "params", "episode", "step")

    def __len__(self) -> int:
        return int(self.before.shape[0])

    @property
    def behavior_names(self) -> list[str]:
        return [b["name"] for b in self.behaviors]

    @property
    def effects(self) -> np.ndarray:
        """f_effect = f^(b) - f^() per row."""
        return self.after - self.before

    def validate(self) -> None:
        """Raise ValueError with one sentence if the arrays do not fit together."""
        n = len(self)
        d = len(self.schema)
        if self.before.ndim != 2 or self.before.shape[1] != d:
            raise ValueError(f"interactions have {self.before.shape[-1]} features but the schema names {d}")
        for name in self.ARRAYS:
            if getattr(self, name).shape[0] != n:
                raise ValueError(f"interactions array {name!r} has {getattr(self, name).shape[0]} rows, expected {n}")
        for name, arr in self.truth.items():
            if arr.shape[0] != n:
                raise ValueError(f"ground-truth array {name!r} has {arr.shape[0]} rows, expected {n}")
        if n and (self.behavior.min() < 0 or self.behavior.max() >= len(self.behaviors)):
            raise ValueError("an interaction names a behaviour the file does not list")
        if not (np.isfinite(self.before).all() and np.isfinite(self.after).all()):
            raise ValueError("the interactions hold NaN or infinite features")

    def subset(self, rows: np.ndarray) -> "Interactions":
        rows = np.asarray(rows)
        return Interactions(
            schema=self.schema, behaviors=self.behaviors,
            **{k: getattr(self, k)[rows] for k in self.ARRAYS},
            truth={k: v[rows] for k, v in self.truth.items()},
            shapes=self.shapes, scene=self.scene,
        )

    @classmethod
    def concatenate(cls, parts: list["Interactions"]) -> "Interactions":
        first = parts[0]
        return cls(
            schema=first.schema, behaviors=first.behaviors,
            **{k: np.concatenate([getattr(p, k) for p in parts]) for k in cls.ARRAYS},
            truth={k: np.concatenate([p.truth[k] for p in parts]) for k in first.truth},
            shapes=first.shapes, scene=first.scene,
        )
