"""``afford predict``: perceive a scene, predict what every behaviour would do.

The probabilities and next states are the planner's forward model's
(:class:`afford.plan.forward.ForwardModel`, through :meth:`afford.api.Model.predictions`), so ``predict`` and ``plan`` report the same numbers
for the same step. A model whose labels were given (chapter 5: success or fail) predicts
the result of each behaviour; one whose categories were discovered predicts the effect
category and the entity it leaves behind.
"""

from __future__ import annotations

from typing import Annotated, Optional

import typer
from rich import box
from rich.table import Table

from afford.learning import load_model
from afford.options import AlphaRule, AlphaRuleOpt, EffectModel, Effects, Json, Layout, ModelScene, Objects, SceneSeed, check_scene_source
from afford.output import Output
from afford.plots import PlotFile, check_plot_file
from afford.scenes_io import model_scene, open_world, scene_layout

#: Features named in an entity's title, at most (the JSON has them all).
_TITLED = 6


def _change(now: dict, nxt: dict, shown: int = 2) -> str:
    """The features the step is expected to change most, with the spread: ``y_min -0.142±0.011``."""
    if not nxt["visible"]:
        return "gone from view"
    moves = sorted(((abs(v - now[n]), n, v - now[n]) for n, v in nxt["features"].items() if n in now), reverse=True)
    parts = [f"{n} {d:+.3f}±{nxt.get('spread', {}).get(n, 0.0):.3f}" for size, n, d in moves[:shown] if size >= 0.005]
    return "\n".join(parts) or "none"


def check(model, scene, layout, seed: int, preds: list[dict]) -> dict:
    """Run each behaviour from the same start in the simulator; did the prediction hold?
    Returns what was perceived after each run, by (object, behaviour)."""
    seen = {}
    for entry in preds:
        for name, p in entry["behaviors"].items():
            world = open_world(scene, layout, seed)
            before = world.perceive()
            after = world.act(name, entry["object"], p.get("alpha"))  # the alpha reported, as reported
            seen[(entry["object"], name)] = after
            if model.label_source == "given":
                actual = world.last_result
                p["observed_result"] = model.result_names[actual]
            else:
                effect = after[entry["object"]] - before[entry["object"]]
                actual = int(model.effects[name].assign(effect[None, :])[0])
                p["outcome"] = scene.outcomes[world.history[-1].outcomes[entry["object"]]]
            p["observed_category"] = actual
            p["held"] = actual == p["category"]
    return seen


def draw(path: str, model, world, state, preds: list[dict], seen: dict | None) -> str:
    """``--plot``: the start's range image, and per behaviour the scene from above (each
    object where it is, where that behaviour is predicted to leave it, where it really went)
    or, for results given (chapter 5), each behaviour's chance of success."""
    import numpy as np

    from afford.plots import scene_figure

    schema = model.schema
    if model.label_source == "given":
        names = list(model.result_names)
        good = names.index("success") if "success" in names else None
        results = []
        for name, p in preds[0]["behaviors"].items():
            q = p["probabilities"].get(str(good), 0.0) if good is not None else p["probability"]
            results.append((name, float(q), p.get("observed_result")))
        return scene_figure(path, schema, view=world.start_view, results=results,
                            title="predict: the environment as scanned, and each move's chance")

    def row(entry, p):
        v = np.array(state[entry["object"]], dtype=float)
        for n, value in p["next"]["features"].items():
            v[schema.index(n)] = value
        if schema.visibility_index is not None:
            v[schema.visibility_index] = 1.0 if p["next"]["visible"] else 0.0
        return v

    panels = []
    for name in model.names:
        predicted = np.array(state, dtype=float)
        actual = np.array(state, dtype=float) if seen else None
        for entry in preds:
            if name in entry["behaviors"]:
                predicted[entry["object"]] = row(entry, entry["behaviors"][name])
                if seen:
                    actual[entry["object"]] = seen[(entry["object"], name)][entry["object"]]
        panels.append({"title": f"{name} on each object" + (" (and what it did)" if seen else ""),
                       "start": state, "predicted": predicted, "actual": actual})
    return scene_figure(path, schema, view=world.start_view, panels=panels,
                        title="predict: what the robot saw, and where each behaviour would leave each object")


def predict(
    model: Annotated[str, typer.Argument(help="A model artefact.", metavar="MODEL")],
    scene: ModelScene = None,
    seed: SceneSeed = None,
    objects: Objects = None,
    layout: Layout = None,
    run_check: Annotated[bool, typer.Option("--check", help="Also run each behaviour in the simulator, every one from the same start, and report whether the prediction held.")] = False,
    want: Annotated[Optional[list[str]], typer.Option("--want", help="Inverse query: rank (object, behaviour, alpha) by the probability that one step makes OBJ:FEATURE=VALUE~RANGE hold.")] = None,
    plot: PlotFile = None,
    effects: Effects = EffectModel.members,
    alpha_rule: AlphaRuleOpt = AlphaRule.group,
    json: Json = False,
) -> None:
    """Predict, for every entity the robot sees, what each behaviour would do."""
    check_scene_source(layout, seed, objects=objects)
    check_plot_file(plot)
    loaded = load_model(model)
    loaded.effect_model = effects.value
    loaded.alpha_rule = alpha_rule.value
    if want:
        loaded.check_effects("an inverse query (--want)")
    sc, specs = scene_layout(model_scene(loaded, scene), seed, layout, objects=objects)
    world = open_world(sc, specs, seed or 0)
    state = world.perceive()
    preds = loaded.predictions(state)
    seen = check(loaded, sc, specs, seed or 0, preds) if run_check else None
    result = {"objects": preds, "layout": sc.layout_json(specs), "label_source": loaded.label_source}
    if plot is not None:
        result["plot"] = draw(plot, loaded, world, state, preds, seen)
    if want:
        from afford.api import parse_goal

        goal = parse_goal(want, loaded.schema)
        result["want"] = goal.to_json()
        result["ranking"] = loaded.inverse(state, goal)
    if run_check:
        checks = [p["held"] for e in preds for p in e["behaviors"].values()]
        result["held"] = int(sum(checks))
        result["checked"] = len(checks)

    def render(console):
        given = loaded.label_source == "given"
        cats = {} if given else {n: {c["id"]: c for c in loaded.art.manifest["categories"][n]} for n in loaded.names}
        # an entity is an object when some behaviour acts on one (chapter 5's moves act on the whole scene)
        kind = "object" if any(b.get("target", "object") is not None for b in loaded.behaviors) else "scene"
        for e in preds:
            shown = list(e["features"].items())
            where = ", ".join(f"{k} {v:.2f}" for k, v in shown[:_TITLED]) + (", ..." if len(shown) > _TITLED else "")
            t = Table(title=f"{kind} {e['object']}" + (f": {where}" if where else ""), box=box.SIMPLE_HEAD)
            cols = ["behaviour", "result" if given else "category", "p"]
            if any("alpha" in p for p in e["behaviors"].values()):
                cols.insert(1, "alpha")
            if not given:
                cols += ["members were mostly", "seen", "expected change"]
            if run_check:
                cols.append("in simulation")
            for col in cols:  # words wrap in a narrow terminal; numbers stay whole
                t.add_column(col, no_wrap=col in ("behaviour", "alpha", "category", "p", "result"), overflow="fold")
            for name, p in e["behaviors"].items():
                row = [name, p["result"] if given else str(p["category"]), f"{p['probability']:.2f}"]
                if "alpha" in cols:
                    row.insert(1, ", ".join(f"{a:.2f}" for a in p.get("alpha", ())) or "-")
                if not given:
                    outcomes = cats[name][p["category"]].get("outcomes", {})
                    row += [max(outcomes, key=outcomes.get) if outcomes else "?", "yes" if p["next"]["visible"] else "no",
                            _change(e["features"], p["next"])]
                if run_check:
                    seen = p.get("observed_result", p["observed_category"])
                    row.append(("[green]held" if p["held"] else f"[red]was {seen}") + "[/]"
                               + (f" ({p['outcome']})" if "outcome" in p else ""))
                t.add_row(*row)
            console.print(t)
        if run_check:
            console.print(f"predictions held in {result['held']} of {result['checked']} runs")
        if want:
            t = Table(title=f"most likely to make {' and '.join(result['want'])} hold in one step", box=box.SIMPLE_HEAD)
            for col in ("object", "behaviour", "alpha", "probability"):
                t.add_column(col)
            for r in result["ranking"][:10]:
                t.add_row(str(r["object"]), r["behavior"], ", ".join(f"{a:.2f}" for a in r["alpha"]) or "-", f"{r['probability']:.3f}")
            console.print(t)

    Output(json).result(result, render)
