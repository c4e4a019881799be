"""``afford demo``: the main job on the built-in table scene, stage by stage."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from afford_cli.artifacts import artifact_bytes, read_artifact, write_artifact
from afford_cli.commands.explore import make_scene, run_explore, summary
from afford_cli.commands.inspect import describe, render
from afford_cli.datasets import interactions_members
from afford_cli.options import Seed, Workers
from afford_cli.output import Output


def demo(
    out_dir: Annotated[Path, typer.Option("--out", help="Directory for the demo's artefacts.")] = Path("demo-out"),
    interactions: Annotated[int, typer.Option("--interactions", min=1, help="Interactions to explore.")] = 2000,
    seed: Seed = 0,
    workers: Workers = 2,
) -> None:
    """Explore the table scene and inspect what was recorded."""
    out = Output()
    out_dir.mkdir(parents=True, exist_ok=True)
    console = out.report
    console.rule("[bold]1. explore: the robot pushes and lifts random objects")
    scene = make_scene("table")
    data, seconds = run_explore(out, scene, episodes=None, interactions=interactions, seed=seed,
                                workers=workers, max_steps=10)
    path = out_dir / "table.interactions.afford"
    arrays, meta = interactions_members(data)
    write_artifact(str(path), artifact_bytes("interactions", arrays, meta, seed=seed))
    s = summary(data, seconds)
    console.print(f"recorded {s['interactions']} interactions in {s['episodes']} episodes "
                  f"({s['interactions_per_second']}/s) -> {path}")
    console.rule("[bold]2. inspect: what the file holds, verified")
    render(console, describe(read_artifact(str(path))))
