"""``afford inspect``: report and verify any artefact."""

from __future__ import annotations

from rich.table import Table

from afford.artifacts import Artifact, read_artifact, reading
from afford.errors import AffordError
from afford.datasets import behaviour_counts, interactions_from_artifact, outcome_table
from afford.options import InputPath, Json
from afford.output import Output
from afford.plots import PlotDir, artefact_plots, plot_directory, written
from afford.reports import render_categories, render_outcome_table, render_result_rates
from afford.features import FeatureSchema


def describe(art: Artifact) -> dict:
    """Everything a report shows, as plain data."""
    m = art.manifest
    info = {
        "kind": art.kind,
        "schema_version": m["schema_version"],
        "afford_version": m.get("afford_version"),
        "sha256": art.sha256,
        "created": m.get("created"),
        "command": m.get("command"),
        "seed": m.get("seed"),
        "parents": m.get("parents", []),
        "verified": art.sealed,  # every member's checksum always is; the manifest's only when sealed
        "sealed": art.sealed,
        "members": sorted(m.get("members", {})),
        "features": [],
        "behavior_names": [b["name"] for b in m.get("behaviors", [])],
    }
    if "schema" in m:
        try:
            schema = FeatureSchema.from_json(m["schema"])
        except (KeyError, TypeError, ValueError, AttributeError):
            raise AffordError(f"{art.source} has a malformed feature schema; it is corrupt or was edited") from None
        info["features"] = [{"name": n, "channel": c} for n, c in zip(schema.names, schema.channels)]
        info["channels"] = [{"channel": ch, "n": int(idx.size), "unit": schema.channel(ch).unit,
                             "tolerance": schema.channel(ch).tolerance} for ch, idx in schema.channel_groups()]
        info["visibility"] = schema.visibility
        info["histograms"] = len(schema.histograms)
        info["histogram_columns"] = [list(h) for h in schema.histograms]
    if "label_source" in m or "n_interactions" in m:
        info["label_source"] = m.get("label_source", "discovered")
    if m.get("result_rates"):
        info["result_rates"] = m["result_rates"]
    if m.get("relevance"):
        info["n_selected"] = {name: len(r.get("selected", [])) for name, r in m["relevance"].items()}
    if art.kind == "model" and m.get("label_source") == "given":
        info["predictors"] = {name: {"results": {c["name"]: c["count"] for c in m.get("categories", {}).get(name, [])},
                                     "cv": m.get("cv", {}).get(name, {})} for name in info["behavior_names"]}
    if "effects" in m:
        info["behaviors"] = _behaviour_reports(m)
    if art.kind == "model":
        info["training"] = m.get("training", {})
    if "n_interactions" in m:
        data = interactions_from_artifact(art)
        info.update({
            "n_interactions": m["n_interactions"],
            "n_episodes": m.get("n_episodes"),
            "episode_range": [m["episodes"]["start"], m["episodes"]["stop"]] if isinstance(m.get("episodes"), dict) else None,
            "online": m.get("online"),
            "counts": behaviour_counts(data),
            "outcomes": outcome_table(data),
            "scene": m.get("scene", {}),
        })
    return info


def render(console, info: dict) -> None:
    head = Table(title=f"afford artefact: {info['kind']}", show_header=False)
    head.add_column("field", style="bold")
    head.add_column("value")
    for key in ("kind", "schema_version", "afford_version", "sha256", "created", "seed"):
        head.add_row(key, str(info.get(key)))
    head.add_row("command", " ".join(info.get("command") or []))
    head.add_row("parents", ", ".join(f"{p['kind']} {p['sha256'][:12]}" for p in info["parents"]) or "none")
    head.add_row("checksums", "verified" if info["sealed"] else
                 "members verified; the manifest is unsealed (schema 1), so an edit to it would not show")
    if "n_interactions" in info:
        span = info.get("episode_range")
        head.add_row("interactions", f"{info['n_interactions']} in {info['n_episodes']} episodes" + (
            f" (episodes {span[0]}-{span[1] - 1}: a shard 'afford merge' can join)" if span else ""))
        head.add_row("scene", str(info["scene"].get("name", "?")))
        online = info.get("online")
        if isinstance(online, dict) and isinstance(online.get("behaviors"), dict):
            head.add_row("explored", f"out of curiosity ({online.get('strategy')}, bootstrap {online.get('bootstrap')}): "
                         f"of {online.get('candidates')} candidates tried " + ", ".join(
                             f"{n} {b.get('tried')}" for n, b in online["behaviors"].items()))
    console.print(head)
    if info["features"]:
        channels: dict[str, list[str]] = {}
        for f in info["features"]:
            channels.setdefault(f["channel"], []).append(f["name"])
        ft = Table(title=f"features ({len(info['features'])})")
        ft.add_column("channel")
        ft.add_column("n", justify="right")
        ft.add_column("names")
        for ch, names in channels.items():
            shown = ", ".join(names) if len(names) <= 8 else ", ".join(names[:3]) + f", ... , {names[-1]}"
            ft.add_row(ch, str(len(names)), shown)
        console.print(ft)
    if info.get("result_rates"):
        render_result_rates(console, info["result_rates"])
    if info.get("predictors"):
        pt = Table(title="predictors of the given results")
        for col in ("behaviour", "training rows by result", "features", "setting", "held-out accuracy"):
            pt.add_column(col)
        for name, p in info["predictors"].items():
            cv = p["cv"]
            pt.add_row(name, ", ".join(f"{k} {v}" for k, v in p["results"].items()), str(info.get("n_selected", {}).get(name, "?")),
                       _setting(cv), _held_out(cv))
        console.print(pt)
    if info.get("n_selected"):
        n = len(info["features"])
        console.print("relevant features kept: " + ", ".join(
            f"{b} {k} of {n} ({100 * k / max(n, 1):.1f} %)" for b, k in info["n_selected"].items()))
    if info.get("counts"):
        ct = Table(title="interactions per behaviour")
        ct.add_column("behaviour")
        ct.add_column("count", justify="right")
        for k, v in info["counts"].items():
            ct.add_row(k, str(v))
        console.print(ct)
    if info.get("outcomes"):
        render_outcome_table(console, info["outcomes"])
    if info.get("behaviors"):
        channels = _channels(info["features"])
        for name, report in info["behaviors"].items():
            render_categories(console, name, report["categories"], channels)
            extra = []
            if report.get("selected"):
                extra.append(f"relevant features: {', '.join(report['selected'])}")
            if report.get("cv"):
                cv = report["cv"]
                if cv.get("constant"):
                    extra.append("one effect only: predicted with certainty")
                else:
                    extra.append(f"accuracy {_held_out(cv)}, {_setting(cv)}")
            if report.get("member_effects"):
                me = report["member_effects"]
                k = me.get("k") if isinstance(me.get("k"), dict) else {}
                loo = me.get("loo_error", {}) if isinstance(me.get("loo_error"), dict) else {}
                parts = []
                for ch, kc in k.items():
                    errors = loo.get(ch, {}) if isinstance(loo.get(ch), dict) else {}
                    said = "the prototype" if kc == 0 else f"the {kc} most similar members"
                    if str(kc) in errors and "0" in errors and kc != 0:
                        said += f" (leave-one-out error {errors[str(kc)]:.3f} against the prototype's {errors['0']:.3f})"
                    parts.append(f"{ch}: {said}")
                if parts:
                    extra.append("effect within a category, per channel: " + "; ".join(parts))
            for line in extra:
                console.print(f"  {line}")


def _short(value) -> str:
    """A hyperparameter as a reader wants it: four significant digits (``0.00833``, ``1000``)."""
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _setting(cv: dict) -> str:
    """A predictor's chosen setting: ``C=10, gamma=0.0833`` for an SVM, ``smallest leaf 3`` for a forest."""
    p = cv.get("best_params", {})
    if "min_samples_leaf" in p:
        return f"smallest leaf {p['min_samples_leaf']:g}"
    return f"C={_short(p.get('C', '?'))}, gamma={_short(p.get('gamma', '-'))}"


def _held_out(cv: dict) -> str:
    """The chosen setting's held-out accuracy and how it was held out (folds, or a forest's out-of-bag votes)."""
    if "cv_accuracy" not in cv:
        return "?"
    how = "out-of-bag" if cv.get("validation") == "out-of-bag" else f"{cv.get('n_splits', '?')} folds"
    return f"{100 * cv['cv_accuracy']:.1f} % ({how})"


def _channels(features: list[dict]) -> list[tuple[str, list[str]]]:
    out: dict[str, list[str]] = {}
    for f in features:
        out.setdefault(f["channel"], []).append(f["name"])
    return list(out.items())


def _behaviour_reports(m: dict) -> dict:
    """Per behaviour: categories (id, count, prototype, outcomes), relevance, CV report."""
    reports = {}
    for name, eff in m.get("effects", {}).items():
        cats = m.get("categories", {}).get(name, eff.get("categories", []))
        report = {k: v for k, v in eff.items() if k != "categories"}
        report["categories"] = cats
        rel = m.get("relevance", {}).get(name)
        if rel:
            report["selected"] = rel.get("selected", [])
            if "scores" in rel:
                report["relevance"] = rel["scores"]
        if name in m.get("cv", {}):
            report["cv"] = m["cv"][name]
        members = m.get("member_effects", {}).get(name) if isinstance(m.get("member_effects"), dict) else None
        if isinstance(members, dict):
            report["member_effects"] = {"k": members.get("k"), "loo_error": members.get("loo_error", {})}
        reports[name] = report
    return reports


def _start_images(art: Artifact, info: dict, plot_dir) -> list[str]:
    """The range images of the first episodes' starts, re-simulated (when this afford can
    rebuild the scene the rows were explored in); ``info["range_images"]`` says what they show."""
    from afford.plots import range_images_figure
    from afford.scenes_io import episode_starts

    starts = episode_starts(art.manifest.get("scene", {}), art.manifest.get("seed"), interactions_from_artifact(art))
    info["range_images"] = [{"episode": s["episode"], "objects": len(s["boxes"]),
                             "matches_recording": s["matches_recording"]} for s in starts]
    return [range_images_figure(plot_dir / "range-images.png", starts)] if starts else []


def check_as_used(art: Artifact) -> None:
    """Make the checks the commands that consume ``art`` make (a model's estimators of their
    trusted parts, labels within their categories, a selection within the schema), so that
    ``inspect`` calls verified only what they would open."""
    from afford.learning import LoadedModel, read_effects, read_selection

    if art.kind == "model":
        LoadedModel(art)
        return
    data = interactions_from_artifact(art)
    if art.kind in ("effects", "features"):
        read_effects(art, data)
    if art.kind == "features":
        read_selection(art, data)


def inspect(path: InputPath, json: Json = False, plots: PlotDir = None) -> None:
    """Report any afford artefact (kind, lineage, features, categories, outcomes) and verify its checksums."""
    out = Output(json)
    plot_dir = plot_directory(plots) if plots is not None else None
    art = read_artifact(path)
    with reading(art):  # a forged manifest (checksums recomputed) is one sentence, not a traceback
        check_as_used(art)
        info = describe(art)
        if plot_dir is not None:
            info["plots"] = artefact_plots(info, plot_dir)
            if "n_interactions" in art.manifest:
                info["plots"] += _start_images(art, info, plot_dir)
        out.result(info, lambda console: render(console, info))
    if plot_dir is not None:
        out.info(written(info["plots"]))
