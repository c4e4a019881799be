"""Interactions <-> artefact members, and the summaries reports show."""

from __future__ import annotations

from collections import Counter
from typing import Any

import numpy as np

from afford.artifacts import Artifact
from afford.errors import AffordError
from afford.features import OUTCOMES, FeatureSchema, Interactions

__all__ = ["interactions_members", "interactions_from_artifact", "outcome_table", "behaviour_counts", "check_shards",
           "explored_settings", "settings_difference"]

_TRUTH = "truth_"


def behaviour_counts(data: Interactions) -> dict[str, int]:
    counts = np.bincount(data.behavior.astype(int), minlength=len(data.behaviors))
    return {name: int(c) for name, c in zip(data.behavior_names, counts)}


def outcome_table(data: Interactions) -> dict[str, dict[str, dict[str, int]]]:
    """``{behaviour: {shape: {label: count}}}`` from ground truth, over the shapes the data
    hold (a scene drawing from a shared list of shapes, as the crane does, does not list
    the ones it never places)."""
    table: dict[str, dict[str, dict[str, int]]] = {}
    if "outcome" not in data.truth or "shape" not in data.truth:
        return table
    keys = Counter(zip(data.behavior.tolist(), data.truth["shape"].tolist(), data.truth["outcome"].tolist()))
    present = set(data.truth["shape"].tolist())
    for b, name in enumerate(data.behavior_names):
        table[name] = {}
        for s, shape in enumerate(data.shapes):
            if s not in present:
                continue
            table[name][shape] = {label: int(keys.get((b, s, o), 0)) for o, label in enumerate(data.outcome_names)}
    return table


def result_rates(data: Interactions) -> dict[str, dict[str, float]]:
    """Per behaviour, the share of each given result (``{}`` for discovered labels)."""
    if data.result is None:
        return {}
    out = {}
    for b, name in enumerate(data.behavior_names):
        r = data.result[data.behavior == b]
        out[name] = {label: round(float(np.mean(r == i)), 4) if r.size else 0.0
                     for i, label in enumerate(data.result_names)}
    return out


def interactions_members(data: Interactions) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
    """Arrays and manifest entries of an ``interactions`` artefact (each entity once)."""
    data = data.compact()
    data.validate()
    arrays = {k: getattr(data, k) for k in Interactions.ARRAYS}
    arrays["entities"] = data.entities
    if data.after_index is not None:
        arrays["after_index"] = data.after_index
    if data.result is not None:
        arrays["result"] = data.result
    arrays.update({_TRUTH + k: v for k, v in data.truth.items()})
    meta = {
        "schema": data.schema.to_json(),
        "behaviors": data.behaviors,
        "scene": data.scene,
        "shapes": list(data.shapes),
        "outcome_labels": list(data.outcome_names) if "outcome" in data.truth else [],
        "label_source": data.label_source,
        "result_names": list(data.result_names),
        "n_interactions": len(data),
        "n_episodes": int(np.unique(data.episode).size),
        "n_entities": int(data.entities.shape[0]),
        "counts": behaviour_counts(data),
    }
    if data.result is not None:
        meta["result_rates"] = result_rates(data)
    return arrays, meta


def interactions_from_artifact(art: Artifact) -> Interactions:
    """Rebuild Interactions from an artefact that carries its rows."""
    m = art.manifest
    a = art.arrays
    try:
        schema = FeatureSchema.from_json(m["schema"])
        rest = dict(
            truth={k[len(_TRUTH):]: v for k, v in a.items() if k.startswith(_TRUTH)},
            shapes=list(m.get("shapes", [])),
            scene=dict(m.get("scene", {})),
            result=a.get("result"),
            result_names=[str(r) for r in m.get("result_names", [])],
            outcome_names=[str(o) for o in m.get("outcome_labels") or OUTCOMES],
        )
        rows = {k: a[k] for k in ("behavior", "params", "episode", "step")}
        if "entities" in a:
            data = Interactions(schema=schema, behaviors=list(m["behaviors"]), entities=a["entities"],
                                before_index=a["before_index"], after_index=a.get("after_index"), **rows, **rest)
        else:  # written before entities were stored once: a before and an after per row
            data = Interactions.from_rows(schema, list(m["behaviors"]), a["before"], a["after"], **rows, **rest)
    except (KeyError, TypeError, ValueError, AttributeError, IndexError) as exc:
        why = f"it lacks {exc.args[0]!r}" if isinstance(exc, KeyError) and exc.args else str(exc)
        raise AffordError(f"{art.source} does not hold interaction rows that fit together ({why}); "
                          "it is corrupt or was edited") from None
    try:
        data.validate()
    except ValueError as exc:
        raise AffordError(f"{art.source}: {exc}") from None
    _check_counts(art, data)
    return data


def _check_counts(art: Artifact, data: Interactions) -> None:
    """The manifest's counts are the arrays' (an edited manifest, resealed, is caught here)."""
    m = art.manifest
    actual = {"n_interactions": len(data), "n_episodes": int(np.unique(data.episode).size),
              "n_entities": int(data.entities.shape[0])}
    for key, value in actual.items():
        if key in m and m[key] != value:
            raise AffordError(f"{art.source} is corrupt or was edited: its manifest says {key} {m[key]!r}, "
                              f"its arrays hold {value}")
    if "counts" in m and m["counts"] != behaviour_counts(data):
        raise AffordError(f"{art.source} is corrupt or was edited: its manifest's behaviour counts are not its arrays'")


def explored_settings(scene: dict | None) -> dict:
    """A scene's description without its learner defaults (how to cluster and train): what
    decides the rows an exploration makes, which shards to merge and a journal to resume
    must share."""
    return {k: v for k, v in (scene or {}).items() if k != "learner"}


def settings_difference(a: dict, b: dict, most: int = 3) -> str:
    """The first ``most`` settings in which ``a`` and ``b`` differ, as ``key: x and y; ...``."""
    s0, s1 = _flat(a), _flat(b)
    differ = sorted(k for k in set(s0) | set(s1) if s0.get(k) != s1.get(k))
    shown = "; ".join(f"{k}: {s0.get(k, '(unset)')} and {s1.get(k, '(unset)')}" for k in differ[:most])
    return shown + ("; ..." if len(differ) > most else "")


def _flat(settings: dict, prefix: str = "") -> dict:
    """Nested settings as one level of dotted keys (``world.camera.noise``)."""
    out = {}
    for k, v in settings.items():
        if isinstance(v, dict):
            out.update(_flat(v, f"{prefix}{k}."))
        else:
            out[f"{prefix}{k}"] = v
    return out


def check_shards(shards: list[tuple[Artifact, Interactions]]) -> tuple[list[int], tuple[int, int], int | None]:
    """Shards of one exploration, checked: the order to join them in, the episodes they
    cover together, and their seed. Each must have been explored by episodes (its manifest's
    ``episodes``), all of one scene, schema and seed, with no episode twice and none missing."""
    spans = []
    for art, data in shards:
        ep = art.manifest.get("episodes")
        if not isinstance(ep, dict) or not {"start", "stop"} <= set(ep):
            raise AffordError(f"{art.source} is no shard: it was not explored by episodes (explore shards with "
                              "--episode-start and --episode-count)")
        start, stop = int(ep["start"]), int(ep["stop"])
        if len(data) and (data.episode.min() < start or data.episode.max() >= stop):
            raise AffordError(f"{art.source} is corrupt or was edited: it holds episodes outside {start}-{stop - 1}")
        spans.append((start, stop))
    (first, a), m0 = shards[0], shards[0][0].manifest
    for art, data in shards[1:]:
        m = art.manifest
        x, y = m0.get("scene", {}).get("name"), m.get("scene", {}).get("name")
        if x != y:
            raise AffordError(f"{first.source} and {art.source} are of different scenes ({x} and {y})")
        explored0, explored1 = explored_settings(m0.get("scene")), explored_settings(m.get("scene"))
        if explored0 != explored1:
            raise AffordError(f"{first.source} and {art.source} were explored with different scene settings "
                              f"({settings_difference(explored0, explored1)})")
        if m0.get("seed") != m.get("seed"):
            raise AffordError(f"{first.source} and {art.source} were explored with different seeds "
                              f"({m0.get('seed')} and {m.get('seed')}), so they are not shards of one exploration")
        if a.schema.to_json() != data.schema.to_json() or a.behaviors != data.behaviors:
            raise AffordError(f"{first.source} and {art.source} perceive different features or have different behaviours")
    order = sorted(range(len(shards)), key=lambda i: spans[i])
    for i, j in zip(order, order[1:]):
        (s0, e0), (s1, e1) = spans[i], spans[j]
        if s1 < e0:
            raise AffordError(f"{shards[i][0].source} and {shards[j][0].source} both hold episodes {s1}-{min(e0, e1) - 1}")
        if s1 > e0:
            raise AffordError(f"episodes {e0}-{s1 - 1} are in none of the shards: {shards[i][0].source} ends at "
                              f"{e0 - 1}, {shards[j][0].source} starts at {s1}")
    return order, (spans[order[0]][0], spans[order[-1]][1]), m0.get("seed")
