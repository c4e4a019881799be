"""Effects, features and model artefacts: what each learning command adds, and reads back.

``interactions`` -> ``effects`` (each row's category, the fitted categories per behaviour)
-> ``features`` (relevance scores and chosen features per behaviour) -> ``model`` (no raw
rows: prototypes, chosen features, fitted predictors and effect categories, the training
matrices the baselines need, cross-validation reports and category reports).
"""

from __future__ import annotations

import numbers

from typing import Any

import numpy as np

from afford.artifacts import Artifact, dump_estimator, read_artifact, reading
from afford.datasets import interactions_from_artifact, interactions_members
from afford.errors import AffordError
from afford.features import FeatureSchema, Interactions
from afford.learn import TRUSTED_TYPES as PREDICTOR_TYPES

__all__ = [
    "TRUSTED", "read_rows", "effects_members", "read_effects", "features_members", "read_selection",
    "category_report", "model_members", "LoadedModel", "load_model", "search_rows_setting",
]

#: Every type a model file may hold; anything else is refused on load.
TRUSTED = sorted(set(PREDICTOR_TYPES) | {"afford.learn.effects.EffectCategories"})

ROW_KINDS = ("interactions", "effects", "features")

#: What fitted effect categories are built of (their arrays aside): themselves alone.
EFFECT_PARTS = frozenset({"afford.learn.effects.EffectCategories"})


def read_rows(path: str, kinds: tuple[str, ...] = ROW_KINDS) -> tuple[Artifact, Interactions]:
    art = read_artifact(path, kinds)
    return art, interactions_from_artifact(art)


def category_report(data: Interactions, labels: np.ndarray, b: int, prototypes: np.ndarray) -> list[dict]:
    """Per category: id, count, prototype ``{feature: value}``, outcomes ``{label: fraction}``."""
    rows = np.flatnonzero(data.behavior == b)
    out = []
    outcome = data.truth.get("outcome")
    for c in range(prototypes.shape[0]):
        members = rows[labels[rows] == c]
        entry: dict[str, Any] = {
            "id": c,
            "count": int(members.size),
            "prototype": {name: round(float(v), 5) for name, v in zip(data.schema.names, prototypes[c])},
        }
        if outcome is not None and members.size:
            counts = np.bincount(outcome[members], minlength=len(data.outcome_names))
            entry["outcomes"] = {label: round(float(n / members.size), 4)
                                 for label, n in zip(data.outcome_names, counts) if n}
        out.append(entry)
    return out


def _blob_name(kind: str, behavior: str) -> str:
    return f"{kind}.{behavior}"


def effects_members(data: Interactions, labels: np.ndarray, models: dict, settings: dict) -> tuple[dict, dict, dict]:
    arrays, meta = interactions_members(data)
    arrays["category"] = labels.astype(np.int16)
    blobs = {_blob_name("effects", name): dump_estimator(ec) for name, ec in models.items()}
    summary = {}
    for b, name in enumerate(data.behavior_names):
        ec = models[name]
        summary[name] = {
            **settings,
            "n_categories": int(ec.n_categories_),
            "pruned_rows": int((labels[data.behavior == b] < 0).sum()),
            "channel_categories": {ch: int(np.asarray(v).size) for ch, v in ec.channel_counts_.items()},
            "categories": category_report(data, labels, b, ec.prototypes_),
        }
    meta["effects"] = summary
    return arrays, meta, blobs


def read_effects(art: Artifact, data: Interactions) -> tuple[np.ndarray, dict | None]:
    """Each row's label, and the fitted effect categories per behaviour.

    Labels come from one of two sources: categories ``afford cluster`` discovered (then
    the fitted categories come too), or results given with the interactions, the robot's
    own success readings (then there are no effect categories: ``None``).
    """
    if "category" in art.arrays and "effects" in art.manifest:
        from afford.learn.effects import EffectCategories

        with reading(art):
            models = {name: art.estimator(_blob_name("effects", name), TRUSTED, EffectCategories, EFFECT_PARTS)
                      for name in data.behavior_names}
            raw = art.arrays["category"]
            if raw.dtype.kind not in "iu":
                raise AffordError(f"{art.source}: category holds {raw.dtype} values where whole category numbers "
                                  "belong; it is corrupt or was edited")
            labels = raw.astype(int)
            if labels.shape != (len(data),) or (labels.size and (labels.min() < -1 or labels.max() >= 10_000)):
                raise AffordError(f"{art.source}: category does not give one category per interaction; "
                                  "it is corrupt or was edited")
            for b, name in enumerate(data.behavior_names):
                n = int(models[name].n_categories_)
                mine = labels[data.behavior == b]
                if mine.size and mine.max() >= n:
                    raise AffordError(f"{art.source}: category gives {name} category {int(mine.max())}, but {name} "
                                      f"has {n} (0-{n - 1}, -1 for a dropped row); it is corrupt or was edited")
        return labels, models
    if data.result is not None:
        return data.result.astype(int), None
    raise AffordError(f"{art.source} holds no labels: its effects have no categories yet (run 'afford cluster' "
                      "on it first) and it gives no results")


def features_members(art: Artifact, data: Interactions, relevance: dict, settings: dict) -> tuple[dict, dict, dict]:
    arrays = dict(art.arrays)
    meta = {k: v for k, v in art.manifest.items() if k not in _MANIFEST_OWN}
    summary = {}
    for name, fr in relevance.items():
        arrays[f"selected.{name}"] = np.asarray(fr.selected_, dtype=np.int32)
        arrays[f"relevance.{name}"] = np.asarray(fr.scores_, dtype=np.float32)
        summary[name] = {**settings, "selected": [data.schema.names[i] for i in fr.selected_],
                         "scores": {data.schema.names[i]: round(float(fr.scores_[i]), 5) for i in fr.ranking_}}
        if getattr(fr, "parameter_scores_", None):
            # the behaviour's parameters were candidates too: their score and rank among the features
            summary[name]["parameters"] = {p: {"score": round(score, 5), "rank": rank}
                                           for p, (score, rank) in fr.parameter_scores_.items()}
    meta["relevance"] = summary
    return arrays, meta, dict(art.blobs)


def read_selection(art: Artifact, data: Interactions) -> dict[str, np.ndarray]:
    """Chosen feature indices per behaviour (all features for an effects artefact)."""
    if art.kind == "features":
        d = len(data.schema)
        out = {}
        with reading(art):
            for b, name in enumerate(data.behavior_names):
                out[name] = _feature_indices(art, f"selected.{name}", d)
                if out[name].size == 0 and not data.behaviors[b].get("parameters"):
                    # the predictor would have no input at all
                    raise AffordError(f"{art.source}: selected.{name} is empty; it is corrupt or was edited")
        return out
    return {name: np.arange(len(data.schema)) for name in data.behavior_names}


def _feature_indices(art: Artifact, member: str, d: int) -> np.ndarray:
    """Array ``member``: integer indices of features, each within the schema's ``d``."""
    idx = art.arrays[member]
    if idx.ndim != 1 or idx.dtype.kind not in "iu" or (idx.size and (idx.min() < 0 or idx.max() >= d)):
        raise AffordError(f"{art.source}: {member} names features outside the schema's {d}; "
                          "it is corrupt or was edited")
    return idx.astype(int)


# manifest fields every artefact writes for itself
_MANIFEST_OWN = {"format", "kind", "schema_version", "afford_version", "created", "command", "seed", "parents", "members"}


def clustering_settings(scene: dict, schema, source: str, *, method: str | None = None, k: int | dict | None = None,
                        channels: list[str] | str | None = None, k_max: int | None = None) -> dict:
    """How to discover the effect categories of a scene so described (``scene``, its
    ``describe()``; ``schema``, its perception): the options given, else the scene's own
    (``clustering`` in its description), else the hierarchical method with every channel
    and ``k_max`` 5; checked, each mistake one sentence naming ``source``. Returns
    ``{"method", "k", "channels", "k_max"}``."""
    own = scene.get("clustering") or {}
    if method is None:  # the scene's own clustering; a k given here overrides its k
        method = own.get("method", "hierarchical")
        if own.get("k"):
            k = {**own["k"], **({} if k is None else k if isinstance(k, dict) else {"*": k})}
    if channels is None and method == "hierarchical":
        channels = own.get("channels")
        if channels is not None and (not isinstance(channels, list) or not all(isinstance(c, str) for c in channels)):
            raise AffordError(f"{source}: its scene's clustering channels must be a list of channel names")
    if k_max is None:
        k_max = own.get("k_max", 5)
        if not isinstance(k_max, int) or isinstance(k_max, bool) or not 1 <= k_max <= 20:
            raise AffordError(f"{source}: its scene's clustering k_max must be a whole number 1-20, got {k_max!r}")
    if channels is not None:
        channels = [channels] if isinstance(channels, str) else [str(c) for c in channels]
        known = list(dict.fromkeys(schema.channels))
        unknown = [c for c in channels if c not in known]
        if unknown or not channels:
            raise AffordError(f"no effect channel {', '.join(map(repr, unknown)) or 'given'} in {source}; "
                              f"its channels are {', '.join(known)}")
        if method != "hierarchical":
            raise AffordError("--channels goes with the hierarchical method (k-means clusters every channel at once)")
    if k is not None and method != "kmeans":
        raise AffordError("a k goes with the k-means method (--method kmeans)")
    return {"method": method, "k": k, "channels": channels, "k_max": k_max}


def _scene_learner(scene: dict) -> dict:
    """The scene's learner settings (``learner`` in its description), or none."""
    learner = scene.get("learner")
    return learner if isinstance(learner, dict) else {}


def learner_settings(art: Artifact | None, data: Interactions | dict, kernel: str | None = None,
                     folds: int | None = None) -> tuple[str, int]:
    """The kernel and folds to learn ``data`` with (interactions, or a scene's description):
    those given, else the scene's (``learner`` in its configuration), else the RBF kernel
    and 3 folds."""
    learner = _scene_learner(data if isinstance(data, dict) else data.scene)
    kernel = kernel if kernel is not None else str(learner.get("kernel", "rbf"))
    if kernel not in ("rbf", "linear", "forest"):
        raise AffordError(f"{art.source if art else 'the data'} asks for an unknown kernel {kernel!r}; give --kernel")
    try:
        folds = folds if folds is not None else int(learner.get("folds", 3))
    except (TypeError, ValueError):
        raise AffordError(f"{art.source if art else 'the data'} asks for a number of folds that is not a number; "
                          "give --folds") from None
    return kernel, folds


def search_rows_setting(art: Artifact | None, data: Interactions, search_rows: int | None = None) -> int | None:
    """Rows the grid search may cross-validate on, per behaviour: the number given, else the
    scene's (``learner`` in its configuration, ``"search_rows"``), else every row (None)."""
    value = search_rows if search_rows is not None else _scene_learner(data.scene).get("search_rows")
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or value < 10:
        if search_rows is not None:
            raise AffordError(f"search_rows {value!r} is not a whole number of at least 10")
        raise AffordError(f"{art.source if art else 'the data'} asks the grid search for {value!r} rows, not a "
                          "whole number of at least 10; give --search-rows")
    return int(value)


SCORES = ("accuracy", "log_loss")


def selection_score(art: Artifact | None, data: Interactions, score: str | None = None) -> str:
    """What ReliefF's ranking cut scores: the one given, else the scene's (``learner`` in its
    configuration, ``"score"``), else accuracy."""
    score = score if score is not None else _scene_learner(data.scene).get("score", "accuracy")
    if score not in SCORES:
        raise AffordError(f"{art.source if art else 'the data'} asks for an unknown selection score {score!r}; "
                          "give --score")
    return str(score)


def result_report(data: Interactions, labels: np.ndarray, b: int) -> list[dict]:
    """Per given result: id, name and count (the categories of a model whose labels were given)."""
    rows = np.flatnonzero(data.behavior == b)
    return [{"id": i, "name": name, "count": int((labels[rows] == i).sum())} for i, name in enumerate(data.result_names)]


def model_members(art: Artifact, data: Interactions, labels: np.ndarray, effects: dict | None, selected: dict,
                  predictors: dict, settings: dict, known: dict | None = None,
                  members: dict | None = None) -> tuple[dict, dict, dict]:
    from afford.learn.affordances import behaviour_rows, known_columns, parameters_of, predictor_inputs

    arrays, blobs, cv, categories, member_meta = {}, {}, {}, {}, {}
    for b, name in enumerate(data.behavior_names):
        model = predictors[name]
        rows = behaviour_rows(data, b, labels)
        if effects is not None:
            ec = effects[name]
            arrays[f"prototypes.{name}"] = ec.prototypes_
            blobs[_blob_name("effects", name)] = dump_estimator(ec)
        arrays[f"selected.{name}"] = np.asarray(selected[name], dtype=np.int32)
        arrays[f"train_X.{name}"] = predictor_inputs(data.before_rows(rows), data.params[rows], selected[name], parameters_of(data, b)).astype(np.float32)
        arrays[f"train_y.{name}"] = labels[rows].astype(np.int16)
        blobs[_blob_name("predictor", name)] = dump_estimator(model)
        if known and known.get(name) is not None:
            blobs[_blob_name("known", name)] = dump_estimator(known[name])
            arrays[f"known_selected.{name}"] = known_columns(data.schema).astype(np.int16)
        if members and members.get(name) is not None:
            parts, member_meta[name] = members[name].to_arrays()
            arrays.update({f"members_{part}.{name}": a for part, a in parts.items()})
        cv[name] = model.cv_report_
        categories[name] = (category_report(data, labels, b, effects[name].prototypes_) if effects is not None
                            else result_report(data, labels, b))
    meta = {
        "schema": data.schema.to_json(),
        "behaviors": data.behaviors,
        "scene": data.scene,
        "label_source": "discovered" if effects is not None else "given",
        "result_names": [] if effects is not None else list(data.result_names),
        "training": {**settings, "n_interactions": len(data)},
        "effects": art.manifest.get("effects", {}),
        "relevance": {name: {"selected": [data.schema.names[i] for i in selected[name]]} for name in data.behavior_names},
        "cv": cv,
        "categories": categories,
    }
    if member_meta:
        meta["member_effects"] = member_meta
    return arrays, meta, blobs


class LoadedModel:
    """A model artefact with its estimators loaded (trusted types only, each of its slot's type)."""

    def __init__(self, art: Artifact):
        with reading(art):
            self._load(art)

    def _load(self, art: Artifact) -> None:
        from afford.learn import AffordancePredictor
        from afford.learn.effects import EffectCategories
        from afford.learn.predictors import PARTS

        m = art.manifest
        self.art = art
        self.schema = FeatureSchema.from_json(m["schema"])
        self.behaviors = list(m["behaviors"])
        self.names = [b["name"] for b in self.behaviors]
        self.label_source = str(m.get("label_source", "discovered"))
        self.result_names = [str(r) for r in m.get("result_names", [])]
        self.selected = {n: art.arrays[f"selected.{n}"].astype(int) for n in self.names}
        given = self.label_source == "given"
        self.prototypes = {n: None if given else art.arrays[f"prototypes.{n}"] for n in self.names}
        self.effects = {n: None if given else art.estimator(_blob_name("effects", n), TRUSTED, EffectCategories,
                                                             EFFECT_PARTS) for n in self.names}
        self.predictors = {n: art.estimator(_blob_name("predictor", n), TRUSTED, AffordancePredictor, PARTS)
                           for n in self.names}
        self.known = {n: art.estimator(_blob_name("known", n), TRUSTED, AffordancePredictor, PARTS)
                      if _blob_name("known", n) in art.blobs else None for n in self.names}
        # the features P(known) reads (models from before they had their own: the selected)
        self.known_selected = {n: art.arrays[f"known_selected.{n}"].astype(int) if f"known_selected.{n}" in art.arrays
                               else self.selected[n] for n in self.names}
        d = len(self.schema)
        for n in self.names:
            for what in (f"selected.{n}", f"known_selected.{n}"):
                if what in art.arrays:
                    _feature_indices(art, what, d)
            if not given and (self.prototypes[n].ndim != 2 or self.prototypes[n].shape[1] != d
                              or self.prototypes[n].dtype.kind != "f"):
                raise AffordError(f"{art.source}: prototypes.{n} does not have the schema's {d} features; "
                                  "it is corrupt or was edited")
            if art.arrays.get(f"train_y.{n}") is not None and art.arrays[f"train_y.{n}"].dtype.kind not in "iu":
                raise AffordError(f"{art.source}: train_y.{n} does not hold integers; it is corrupt or was edited")
            width = len(self.selected[n]) + sum(2 if p.get("periodic") else 1 for p in self.parameters(n))
            for slot, est, cols in (("predictor", self.predictors[n], width),
                                    ("known", self.known[n], len(self.known_selected[n]) + width - len(self.selected[n]))):
                if est is not None and getattr(est, "n_features_in_", cols) != cols:
                    raise AffordError(f"{art.source}: {slot}.{n} reads {est.n_features_in_} features where the model "
                                      f"gives it {cols}; it is corrupt or was edited")
            tx, ty = art.arrays.get(f"train_X.{n}"), art.arrays.get(f"train_y.{n}")
            if tx is not None and (tx.ndim != 2 or tx.shape[1] != width or ty is None or ty.shape != (tx.shape[0],)):
                raise AffordError(f"{art.source}: train_X.{n} and train_y.{n} are not a table of the predictor's "
                                  f"{width} inputs with one label per row; it is corrupt or was edited")
            cats = m.get("categories", {}).get(n) if isinstance(m.get("categories"), dict) else None
            expected = len(self.result_names) if given else self.prototypes[n].shape[0]
            if cats is not None and len(cats) != expected:
                raise AffordError(f"{art.source} is corrupt or was edited: its manifest lists {len(cats)} categories "
                                  f"of {n}, its arrays {expected}")
        for key, a in sorted(art.arrays.items()):
            if (key.startswith("prototypes.") or key.startswith("members_")) and a.dtype.kind == "f" \
                    and not np.isfinite(a).all():
                raise AffordError(f"{art.source}: {key} holds values that are not finite numbers (NaN or "
                                  "infinity); it is corrupt or was edited")
        self.members = {n: self._members(art, n) for n in self.names}

    def _members(self, art: Artifact, name: str):
        """Behaviour ``name``'s member effects (None in models from before they existed)."""
        from afford.learn.members import MemberEffects

        meta = art.manifest.get("member_effects", {})
        if not isinstance(meta, dict) or name not in meta:
            return None
        parts = {part: art.arrays.get(f"members_{part}.{name}") for part in ("Z", "E", "labels", "shift", "weight")}
        try:
            if any(a is None for a in parts.values()) or not isinstance(meta[name], dict):
                raise ValueError("parts are missing")
            for part in ("Zu", "Eu"):  # the pool of discarded members: models from before it have none
                if f"members_{part}.{name}" in art.arrays:
                    parts[part] = art.arrays[f"members_{part}.{name}"]
            members = MemberEffects.from_arrays(parts, meta[name])
        except ValueError:
            raise AffordError(f"{art.source}: the member effects of {name} do not fit together; "
                              "it is corrupt or was edited") from None
        d = len(self.schema)
        width = d + sum(2 if p.get("periodic") else 1 for p in self.parameters(name))
        if members.Z_.shape[1] != width or members.E_.shape[1] != d or (
                members.labels_.size and members.labels_.max() >= self.prototypes[name].shape[0]):
            raise AffordError(f"{art.source}: the member effects of {name} do not match its schema and categories; "
                              "it is corrupt or was edited")
        return members

    def parameters(self, name: str) -> list[dict]:
        return list(self.behaviors[self.names.index(name)].get("parameters", []))

    def check_effects(self, what: str) -> None:
        """Refuse, in one sentence, a use that needs predicted effects from a model whose labels were given."""
        if self.label_source == "given":
            raise AffordError(f"{what} needs a model that predicts effects, but this model's labels were given "
                              f"({'/'.join(self.result_names)}): it predicts whether a behaviour succeeds, not what changes")

    def check_schema(self, schema: FeatureSchema, what: str) -> None:
        if schema != self.schema:
            raise AffordError(f"{what} has another feature schema than the model ({len(schema)} features "
                              f"against {len(self.schema)}); use data perceived the way the model's were")


def load_model(path: str):
    """The model artefact at ``path``, as the API's :class:`afford.api.Model`."""
    from afford.api import Model

    return Model(read_artifact(path, "model"))


def forward_model(model: LoadedModel, min_probability: float = 0.02, effects: str = "members", alpha_rule: str = "group"):
    """The planner's forward model of a loaded model artefact (``effects``: ``members`` or
    ``prototype``, :class:`afford.plan.forward.ForwardModel`)."""
    from afford.plan.forward import BehaviorModel, ForwardModel

    behaviors = []
    for b, name in enumerate(model.names):
        spec = model.behaviors[b]
        params = [(float(p["low"]), float(p["high"])) for p in spec.get("parameters", [])]
        behaviors.append(BehaviorModel(name, model.predictors[name], model.selected[name], model.prototypes[name], params,
                                       known=model.known[name], known_selected=model.known_selected[name],
                                       periodic=tuple(bool(p.get("periodic")) for p in spec.get("parameters", [])),
                                       target=spec.get("target", "object"), members=model.members[name]))
    return ForwardModel(behaviors, model.schema, min_probability=min_probability, effects=effects, alpha_rule=alpha_rule)
