"""``afford evaluate``: a model on held-out interactions, against baselines from the same run."""

from __future__ import annotations

from typing import Annotated

import numpy as np
import typer

from afford.artifacts import read_artifact
from afford.datasets import interactions_from_artifact
from afford.errors import AffordError
from afford.learning import load_model
from afford.options import Json, Seed
from afford.plan.forward import SCENE
from afford.output import Output
from afford.plots import PlotDir, evaluation_plots, plot_directory, written
from afford.reports import render_metrics


def evaluate_model(model, data, baselines: bool, seed: int = 0, not_scored: dict | None = None) -> dict:
    """Per behaviour: accuracy, log loss, Brier, ECE, confusion, reliability bins (and baselines).

    A behaviour the data cannot score (none of its interactions, or none of a kind the
    model knows) is left out, with the reason in ``not_scored`` (where given); data that
    score none of the model's behaviours are refused."""
    from afford.learn import baseline_scores, evaluate_predictions
    from afford.learn.affordances import predictor_inputs
    from afford.learn.evaluate import reliability_bins

    model.check_schema(data.schema, "the data")
    skipped: dict[str, str] = {}
    out = {}
    for name in model.names:
        b = data.behavior_names.index(name) if name in data.behavior_names else -1
        rows = np.flatnonzero(data.behavior == b) if b >= 0 else np.zeros(0, dtype=int)
        if rows.size == 0:
            skipped[name] = "the data hold no interactions of it"
            continue
        if model.label_source == "given":
            # the robot's own reading of each held-out interaction
            if data.result is None or data.result_names != model.result_names:
                raise AffordError(f"the model's labels are given results ({'/'.join(model.result_names)}), "
                                  "but the data give none")
            y = data.result[rows].astype(int)
        else:
            # The true category, as training would have labelled the effect; effects of the
            # kinds training discarded (rare ones) are counted apart, not scored.
            if not data.has_after:
                raise AffordError("the model predicts effect categories, but the data record no effects")
            y = model.effects[name].assign(data.effects_of(rows))
        known = y >= 0
        if not known.any():
            skipped[name] = f"none of its {rows.size} interactions falls into a category the model knows"
            continue
        X = predictor_inputs(data.before_rows(rows), data.params[rows], model.selected[name], model.parameters(name))
        predictor = model.predictors[name]
        proba = predictor.predict_proba(X[known])
        m = evaluate_predictions(y[known], proba, predictor.classes_)
        entry = {
            "accuracy": m["accuracy"], "n_test": int(known.sum()), "n_unknown_effects": int((~known).sum()),
            "n_categories": int(predictor.classes_.size), "log_loss": m["log_loss"], "brier": m["brier"],
            "ece": m["ece"], "confusion_matrix": m["confusion_matrix"], "labels": m["labels"],
            "reliability": reliability_bins(y[known], proba, predictor.classes_),
        }
        entry["label_names"] = _label_names(model, name, m["labels"])
        entry.update(_open_set(model, name, data, rows, X, y, predictor))
        if model.label_source != "given":
            entry["effect_error"] = effect_error(model, name, data, rows)
        if baselines:
            arrays = model.art.arrays
            entry["baselines"] = baseline_scores(arrays[f"train_X.{name}"], arrays[f"train_y.{name}"].astype(int),
                                                 X[known], y[known], random_state=seed)
        out[name] = entry
    if not out:
        raise AffordError(f"the data score none of the model's behaviours ({'; '.join(f'{n}: {why}' for n, why in skipped.items())})")
    if not_scored is not None:
        not_scored.update(skipped)
    return out


def _label_names(model, name: str, labels) -> dict[str, str]:
    """Each label's short name: a given result's own, or a description of the category's
    prototype (``reports.category_name``); the ids stay the key."""
    from afford.reports import category_name

    if model.label_source == "given":
        return {str(int(c)): model.result_names[int(c)] for c in labels}
    cats = {int(c["id"]): c for c in model.art.manifest.get("categories", {}).get(name, [])}
    return {str(int(c)): category_name(cats[int(c)].get("prototype", {})) if int(c) in cats else "?" for c in labels}


def effect_error(model, name: str, data, rows: np.ndarray) -> dict:
    """Per channel in metres: how far the predicted next entity lies from the perceived one,
    for the member-effect forward model and the thesis's prototype one.

    The prediction is the planner's main branch: the most probable category's next state
    (:meth:`afford.plan.forward.ForwardModel.apply`). The error of a row is the root mean
    square, over the channel's features, of predicted minus perceived, in centimetres;
    rows where the entity was unseen before or after are left out. ``median_cm`` and
    ``p90_cm`` per model, and ``n``.
    """
    schema = model.schema
    channels = [c.name for c in schema.channel_info if c.unit == "m" and c.name in schema.channel_names]
    before = data.before_rows(rows).astype(float)
    after = before + data.effects_of(rows)
    seen = np.array([schema.visible(f) and schema.visible(g) for f, g in zip(before, after)], dtype=bool)
    out: dict = {}
    if not channels or not seen.any():
        return out
    predicted = {}
    for effects in ("members", "prototype"):
        fm = model.forward(min_probability=0.0, effects=effects)
        b = fm.index(name)
        target = SCENE if fm.behaviors[b].target is None else 0
        if not model.parameters(name):
            fm.prefetch(list(before[seen]), only=b, alpha_only=())
        nxt = []
        for f, alpha in zip(before[seen], data.params[rows][seen]):
            alpha = tuple(float(a) for a in alpha)
            classes, proba = fm.distribution(f, b, alpha)
            best = int(classes[np.argmax(proba)])
            nxt.append(fm.apply(f[None, :], target, b, [best] if target == SCENE else best, alpha)[0])
        predicted[effects] = np.asarray(nxt)
    for channel in channels:
        cols = schema.channel_indices(channel)
        entry = {"n": int(seen.sum())}
        for effects, nxt in predicted.items():
            err = 100.0 * np.sqrt(((nxt[:, cols] - after[seen][:, cols]) ** 2).mean(axis=1))
            entry[effects] = {"median_cm": round(float(np.median(err)), 2), "p90_cm": round(float(np.percentile(err, 90)), 2)}
        out[channel] = entry
    return out


def _open_set(model, name: str, data, rows: np.ndarray, X: np.ndarray, y: np.ndarray, predictor) -> dict:
    """Accuracy over every interaction, an effect of a kind the model discarded counting as
    one more outcome, which the model predicts where P(known) < 0.5 (``accuracy_all``, ``n_all``)."""
    from afford.learn.affordances import predictor_inputs

    guess = predictor.classes_[np.argmax(predictor.predict_proba(X), axis=1)].astype(int)
    known_model = model.known.get(name)
    if known_model is not None:
        Xk = predictor_inputs(data.before_rows(rows), data.params[rows], model.known_selected[name], model.parameters(name))
        p_known = known_model.predict_proba(Xk)[:, list(known_model.classes_).index(1)]
        guess = np.where(p_known < 0.5, -1, guess)
    return {"accuracy_all": round(float(np.mean(guess == y)), 4), "n_all": int(rows.size),
            "predicted_unknown": int((guess < 0).sum())}


def evaluate(
    model: Annotated[str, typer.Argument(help="A model artefact.", metavar="MODEL")],
    data: Annotated[str, typer.Argument(help="Held-out interactions (an 'interactions' artefact, or '-').", metavar="DATA")],
    baselines: Annotated[bool, typer.Option("--baselines", help="Also score majority-class, k-NN and random-forest predictors trained on the model's training rows.")] = False,
    seed: Seed = 0,
    json: Json = False,
    plots: PlotDir = None,
) -> None:
    """Score a model's predictions on held-out interactions: accuracy, log loss, Brier, calibration."""
    if model == "-" and data == "-":
        raise typer.BadParameter("only one of MODEL and DATA can be read from stdin")
    out = Output(json)
    plot_dir = plot_directory(plots) if plots is not None else None
    loaded = load_model(model)
    rows = interactions_from_artifact(read_artifact(data, "interactions"))
    skipped: dict[str, str] = {}
    result = {"behaviors": evaluate_model(loaded, rows, baselines, seed, skipped), "n_interactions": len(rows),
              "not_scored": skipped}
    if plot_dir is not None:
        result["plots"] = evaluation_plots(result["behaviors"], plot_dir)

    def render(console):
        render_metrics(console, result["behaviors"], f"held-out evaluation on {len(rows)} interactions")
        unknown = {n: m["n_unknown_effects"] for n, m in result["behaviors"].items() if m["n_unknown_effects"]}
        if unknown:
            console.print("not scored above (effects of kinds the model discarded as rare): "
                          + ", ".join(f"{n} {c}" for n, c in unknown.items()))
        console.print("over every interaction, a discarded kind predicted where P(known) < 0.5: "
                      + ", ".join(f"{n} {100 * m['accuracy_all']:.1f}% of {m['n_all']}" for n, m in result["behaviors"].items()))
        for n, why in skipped.items():
            console.print(f"not scored: {n} ({why})")

    out.result(result, render)
    if plot_dir is not None:
        out.info(written(result["plots"]))
