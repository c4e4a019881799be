"""Interactions <-> artefact members, and the summaries reports show."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from afford_cli.artifacts import Artifact
from afford_cli.errors import AffordError
from features import OUTCOMES, FeatureSchema, Interactions

__all__ = ["interactions_members", "interactions_from_artifact", "outcome_table", "behaviour_counts"]

_TRUTH = "truth_"


def behaviour_counts(data: Interactions) -> dict[str, int]:
    counts = np.bincount(data.behavior.astype(int), minlength=len(data.behaviors))
    return {name: int(c) for name, c in zip(data.behavior_names, counts)}


def outcome_table(data: Interactions) -> dict[str, dict[str, dict[str, int]]]:
    """``{behaviour: {shape: {label: count}}}`` from ground truth."""
    table: dict[str, dict[str, dict[str, int]]] = {}
    if "outcome" not in data.truth or "shape" not in data.truth:
        return table
    keys = Counter(zip(data.behavior.tolist(), data.truth["shape"].tolist(), data.truth["outcome"].tolist()))
    for b, name in enumerate(data.behavior_names):
        table[name] = {}
        for s, shape in enumerate(data.shapes):
            table[name][shape] = {label: int(keys.get((b, s, o), 0)) for o, label in enumerate(OUTCOMES)}
    return table


def interactions_members(data: Interactions) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Arrays and manifest entries of an ``interactions`` artefact."""
    data.validate()
    arrays = {k: getattr(data, k) for k in Interactions.ARRAYS}
    arrays.update({_TRUTH + k: v for k, v in data.truth.items()})
    meta = {
        "schema": data.schema.to_json(),
        "behaviors": data.behaviors,
        "scene": data.scene,
        "shapes": list(data.shapes),
        "outcome_labels": list(OUTCOMES),
        "n_interactions": len(data),
        "n_episodes": int(np.unique(data.episode).size),
        "counts": behaviour_counts(data),
    }
    return arrays, meta


def interactions_from_artifact(art: Artifact) -> Interactions:
    """Rebuild Interactions from an artefact that carries its rows."""
    m = art.manifest
    try:
        schema = FeatureSchema.from_json(m["schema"])
        data = Interactions(
            schema=schema,
            behaviors=list(m["behaviors"]),
            **{k: art.arrays[k] for k in Interactions.ARRAYS},
            truth={k[len(_TRUTH):]: v for k, v in art.arrays.items() if k.startswith(_TRUTH)},
            shapes=list(m.get("shapes", [])),
            scene=dict(m.get("scene", {})),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise AffordError(f"{art.source} does not hold interaction rows ({exc})") from None
    try:
        data.validate()
    except ValueError as exc:
        raise AffordError(f"{art.source}: {exc}") from None
    return data
