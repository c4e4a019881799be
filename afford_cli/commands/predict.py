"""``afford predict``: perceive a scene, predict every behaviour's effect on every object."""

from __future__ import annotations

from typing import Annotated, Optional

import numpy as np
import typer
from rich import box
from rich.table import Table

from afford_cli.learning import load_model
from afford_cli.options import Json, SceneName
from afford_cli.output import Output
from afford_cli.scenes_io import open_world, scene_objects


def _position(f: np.ndarray, names: list[str]) -> dict:
    return {n: round(float(v), 4) for n, v in zip(names, f)}


def predictions(model, state: np.ndarray) -> list[dict]:
    """For each perceived object and behaviour: category probabilities and the next state."""
    from learn.affordances import predictor_inputs

    pos = model.schema.channel_indices("position")
    pos_names = [model.schema.names[i] for i in pos]
    out = []
    for i, f in enumerate(state):
        entry = {"object": i, "visible": bool(f[0] == 1.0), "position": _position(f[pos], pos_names), "behaviors": {}}
        if f[0] == 1.0:
            for name in model.names:
                k = model.n_params(name)
                X = predictor_inputs(f[None, :], np.zeros((1, k)), model.selected[name], k)
                proba = model.predictors[name].predict_proba(X)[0]
                classes = model.predictors[name].classes_
                best = int(classes[np.argmax(proba)])
                nxt = f + model.prototypes[name][best]
                nxt[0] = min(max(nxt[0], 0.0), 1.0)
                entry["behaviors"][name] = {
                    "category": best,
                    "probability": round(float(proba.max()), 4),
                    "probabilities": {str(int(c)): round(float(p), 4) for c, p in zip(classes, proba)},
                    "next": {"visibility": round(float(nxt[0]), 3), "position": _position(nxt[pos], pos_names)},
                }
        out.append(entry)
    return out


def check(model, scene, specs, seed: int, preds: list[dict]) -> None:
    """Run each behaviour from the same start in the simulator; did the prediction hold?"""
    from features import OUTCOMES

    for entry in preds:
        for name, p in entry["behaviors"].items():
            world = open_world(scene, specs, seed)
            before = world.perceive()
            after = world.act(name, entry["object"])
            effect = after[entry["object"]] - before[entry["object"]]
            actual = int(model.effects[name].assign(effect[None, :])[0])
            p["observed_category"] = actual
            p["held"] = actual == p["category"]
            p["outcome"] = OUTCOMES[world.history[-1].outcomes[entry["object"]]]


def predict(
    model: Annotated[str, typer.Argument(help="A model artefact.", metavar="MODEL")],
    scene: SceneName = "table",
    seed: Annotated[Optional[int], typer.Option("--seed", "-s", min=0, help="Draw a random scene from this seed.")] = None,
    objects: Annotated[int, typer.Option("--objects", min=1, max=6, help="Objects in a drawn scene.")] = 1,
    layout: Annotated[Optional[str], typer.Option("--layout", help="A TOML layout file that pins the scene.")] = None,
    run_check: Annotated[bool, typer.Option("--check", help="Also run each behaviour in the simulator and report whether the prediction held.")] = False,
    want: Annotated[Optional[list[str]], typer.Option("--want", help="Inverse query: rank (object, behaviour, alpha) by the probability that one step makes OBJ:FEATURE=VALUE~RANGE hold.")] = None,
    json: Json = False,
) -> None:
    """Predict, for every object the robot sees, what each behaviour would do to it."""
    if layout is not None and (seed is not None or objects != 1):
        raise typer.BadParameter("--layout pins the scene; it does not go with --seed or --objects")
    if layout is None and seed is None:
        raise typer.BadParameter("give --layout FILE, or --seed S to draw a random scene")
    loaded = load_model(model)
    sc, specs = scene_objects(scene, seed, objects, layout)
    world = open_world(sc, specs, seed or 0)
    state = world.perceive()
    loaded.check_schema(sc.schema, "this scene's perception")
    preds = predictions(loaded, state)
    if run_check:
        check(loaded, sc, specs, seed or 0, preds)
    result = {"objects": preds, "layout": [s.to_dict() for s in specs]}
    if want:
        from afford_cli.commands.plan import parse_goals
        from afford_cli.learning import forward_model
        from plan.search import inverse_query

        goal = parse_goals(want, loaded.schema)
        goal.check_objects(state.shape[0])
        result["want"] = goal.to_json()
        result["ranking"] = inverse_query(forward_model(loaded, min_probability=0.0), state, goal)
    if run_check:
        checks = [p["held"] for e in preds for p in e["behaviors"].values()]
        result["held"] = int(sum(checks))
        result["checked"] = len(checks)

    def render(console):
        cats = {n: {c["id"]: c for c in loaded.art.manifest["categories"][n]} for n in loaded.names}
        for e in preds:
            t = Table(title=f"object {e['object']}: x {e['position']['x_min']:.2f}..{e['position']['x_max']:.2f}, "
                            f"y {e['position']['y_min']:.2f}..{e['position']['y_max']:.2f}, "
                            f"z {e['position']['z_min']:.2f}..{e['position']['z_max']:.2f}", box=box.SIMPLE_HEAD)
            for col in ("behaviour", "category", "p", "members were mostly", "seen after", "centre after (x, y, z)"):
                t.add_column(col, no_wrap=True)
            if run_check:
                t.add_column("in simulation", no_wrap=True)
            for name, p in e["behaviors"].items():
                outcomes = cats[name][p["category"]].get("outcomes", {})
                usual = max(outcomes, key=outcomes.get) if outcomes else "?"
                n = p["next"]["position"]
                centre = ", ".join(f"{(n[a + '_min'] + n[a + '_max']) / 2:.2f}" for a in "xyz")
                row = [name, str(p["category"]), f"{p['probability']:.2f}", usual,
                       "yes" if p["next"]["visibility"] else "no", f"({centre})"]
                if run_check:
                    row.append(("[green]held" if p["held"] else f"[red]was {p['observed_category']}") + f"[/] ({p['outcome']})")
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
