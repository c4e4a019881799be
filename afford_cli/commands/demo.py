"""``afford demo``: the main job on the built-in table scene, stage by stage, then the mobile robot.

Each stage is the same command a user would type (the demo calls the command functions),
so what it prints is what those commands print.
"""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from afford.options import Seed, Workers
from afford.output import Output


def demo(
    out_dir: Annotated[Path, typer.Option("--out", help="Directory for the demo's artefacts.")] = Path("demo-out"),
    interactions: Annotated[int, typer.Option("--interactions", min=200, help="Interactions to learn from (at the table).")] = 2000,
    mobile: Annotated[int, typer.Option("--mobile", min=0, help="Environments the mobile robot explores after the table (0: none).")] = 60,
    seed: Seed = 0,
    workers: Workers = 2,
) -> None:
    """Explore the table scene, learn its affordances, measure them, plan and emulate; then the mobile robot."""
    from afford.scenes_io import make_scene
    from afford.commands import cluster, emulate, evaluate, explore, inspect, plan, predict, select_features, train

    out_dir.mkdir(parents=True, exist_ok=True)
    console = Output().report
    path = {k: str(out_dir / f"{k}.afford") for k in ("interactions", "heldout", "effects", "features", "model")}

    console.rule(f"[bold]1. explore: the robot pushes and lifts random objects ({interactions} interactions)")
    _, s = explore.record(Output(), make_scene("table"), path["interactions"], episodes=None,
                          interactions=interactions, seed=seed, workers=workers)
    console.print(f"recorded {s['interactions']} interactions in {s['episodes']} episodes "
                  f"({s['interactions_per_second']}/s) -> {path['interactions']}; what the file holds, verified:")
    inspect.inspect(path["interactions"])
    console.rule("[bold]2. cluster: effect categories per behaviour, discovered without labels")
    cluster.cluster(path["interactions"], path["effects"], seed=seed)
    console.rule("[bold]3. select-features: what the robot must look at (ReliefF)")
    select_features.select_features(path["effects"], path["features"], seed=seed)
    console.rule("[bold]4. train: calibrated predictors per behaviour")
    train.train(path["features"], path["model"], seed=seed)
    console.rule("[bold]5. evaluate: on interactions the robot has not seen, against baselines")
    explore.explore(output=path["heldout"], interactions=max(200, interactions // 4), seed=seed + 1, workers=workers)
    evaluate.evaluate(path["model"], path["heldout"], baselines=True, seed=seed)
    console.rule("[bold]6. predict: a new scene, checked in simulation")
    predict.predict(path["model"], seed=seed + 2, objects=2, run_check=True)
    console.rule("[bold]7. plan: clear the table, executed in simulation with monitoring")
    plan.plan(path["model"], goal=["*:visibility=0"], seed=seed + 3, objects=2, reachable=True, execute=True)
    console.rule("[bold]8. emulate: shown two objects side by side, bring two others together")
    layouts = Path(__file__).resolve().parents[2] / "examples" / "layouts"
    if (layouts / "close-shown.toml").exists():
        emulate.emulate(path["model"], observe=str(layouts / "close-shown.toml"), start=str(layouts / "close-start-1.toml"))
    else:  # an installed package without the examples directory
        Output().warn(f"example layouts not found in {layouts}; skipping emulation")
    console.rule("[bold]9. inspect: the model file, verified")
    inspect.inspect(path["model"])
    if mobile:
        mob = {k: str(out_dir / f"traverse-{k}.afford") for k in ("interactions", "heldout", "features", "model")}
        console.rule(f"[bold]10. the mobile robot (chapter 5): {mobile} random environments, every move tried, "
                     "each judged by its own odometry")
        explore.explore(output=mob["interactions"], scene="traverse", episodes=mobile, seed=seed, workers=workers)
        console.rule("[bold]11. select-features and train on the given results (no cluster step)")
        select_features.select_features(mob["interactions"], mob["features"], seed=seed)
        train.train(mob["features"], mob["model"], seed=seed)
        console.rule("[bold]12. evaluate on environments it has not seen; predict one and check every move")
        explore.explore(output=mob["heldout"], scene="traverse", episodes=max(10, mobile // 3), seed=seed + 1,
                        workers=workers)
        evaluate.evaluate(mob["model"], mob["heldout"], baselines=True, seed=seed)
        predict.predict(mob["model"], scene="traverse", seed=seed + 2, run_check=True)
    Output().info(f"artefacts in {out_dir}/")
