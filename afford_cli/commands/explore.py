"""``afford explore``: a robot plays with objects; writes an ``interactions`` artefact."""

from __future__ import annotations

import shutil
import time
from enum import Enum
from typing import Annotated, Optional

import typer
from afford.artifacts import check_output, output_is_file, writes_stdout
from afford.errors import AffordError
from afford.datasets import behaviour_counts, outcome_table, result_rates
from afford.reports import render_outcome_table, render_result_rates
from afford.scenes_io import make_scene
from afford.options import Json, OutputPath, SceneName, Seed, Workers
from afford.output import Output


class Backend(str, Enum):
    loky = "loky"
    dask = "dask"


def run_explore(out: Output, scene, *, episodes: int | None, interactions: int | None, seed: int,
                workers: int, max_steps: int | None = None, **where):
    """Explore with a progress bar; returns (data, seconds). ``where``: the API's
    ``episode_start``, ``backend``, ``scheduler``, ``journal`` and ``resume``."""
    from afford.api import explore as run

    total = episodes if episodes is not None else interactions
    unit = "episodes" if episodes is not None else "interactions"
    start = time.perf_counter()
    with out.progress(f"exploring {scene.name} ({unit})", total, lazy=True) as update:
        data = run(scene, episodes=episodes, interactions=interactions, seed=seed, workers=workers,
                   max_steps=max_steps, progress=lambda done, _total: update(done), **where)
    return data, time.perf_counter() - start


def summary(data, seconds: float) -> dict:
    import numpy as np

    return {
        "interactions": len(data),
        "episodes": int(np.unique(data.episode).size),
        "seconds": round(seconds, 3),
        "interactions_per_second": round(len(data) / seconds, 2) if seconds > 0 else None,
        "counts": behaviour_counts(data),
        "label_source": data.label_source,
        "n_features": len(data.schema),
        "channels": {ch: int(idx.size) for ch, idx in data.schema.channel_groups()},
        **({"result_rates": result_rates(data)} if data.result is not None else {}),
    }


def record(out: Output, scene, output: str, *, episodes: int | None, interactions: int | None, seed: int,
           workers: int, max_steps: int | None = None, episode_start: int = 0, backend: str = "loky",
           scheduler: str | None = None, resume: bool = False):
    """Explore, write the ``interactions`` artefact to ``output``; returns (data, summary).
    Finished episodes are journaled beside a file output (``OUT.partial/``) until it is
    written whole; ``resume`` continues an interrupted run's journal."""
    from afford.api import save
    from afford.journal import journal_path

    journal = journal_path(output) if output_is_file(output) else None
    if resume and journal is None:
        raise AffordError("--resume needs -o FILE: the journal it continues lives beside the output file")
    data, seconds = run_explore(out, scene, episodes=episodes, interactions=interactions, seed=seed,
                                workers=workers, max_steps=max_steps, episode_start=episode_start,
                                backend=backend, scheduler=scheduler, journal=journal, resume=resume)
    save(data, output, seed=seed, episodes=None if episodes is None else (episode_start, episode_start + episodes))
    if journal is not None:
        shutil.rmtree(journal, ignore_errors=True)
    result = summary(data, seconds)
    result.update(output=output, backend=backend,
                  episode_range=None if episodes is None else [episode_start, episode_start + episodes])
    return data, result


def explore(
    output: OutputPath,
    scene: SceneName = "table",
    episodes: Annotated[Optional[int], typer.Option("--episodes", "-n", min=1, help="Exploration episodes (trials of the scene's loop: Algorithm 5 or 1); 100 when neither this nor --interactions is given.")] = None,
    interactions: Annotated[Optional[int], typer.Option("--interactions", min=1, help="Stop once this many interactions are recorded (instead of --episodes).")] = None,
    seed: Seed = 0,
    workers: Workers = 1,
    max_steps: Annotated[Optional[int], typer.Option("--max-steps", min=1, help="Most behaviours per episode (scenes that play, Algorithm 5; 10 by default).")] = None,
    size_min: Annotated[Optional[float], typer.Option("--size-min", help="Smallest object dimension, metres (scenes with random objects; the table's default 0.08).")] = None,
    size_max: Annotated[Optional[float], typer.Option("--size-max", help="Largest object dimension, metres (scenes with random objects; the table's default 0.40).")] = None,
    grid: Annotated[Optional[int], typer.Option("--grid", min=1, max=60, help="Grid cells per side of the range image (scenes that perceive grid features: 5 in chapter 5, 30 in chapter 6).")] = None,
    layers: Annotated[Optional[int], typer.Option("--layers", min=1, max=8, help="Overlapping grid layers (4 in chapter 5, 1 in chapter 6).")] = None,
    backend: Annotated[Backend, typer.Option("--backend", help="Where episodes run: loky (processes on this machine) or dask (a LocalCluster of --workers on 127.0.0.1, or the cluster at --scheduler; needs afford[dask]). The same --seed gives the same bytes on either.")] = Backend.loky,
    scheduler: Annotated[Optional[str], typer.Option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler (tcp://HOST:PORT) to explore on, with --backend dask; its workers need afford installed.")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue the interrupted run whose finished episodes are journaled in OUTPUT.partial/ (same options); starts afresh if there is none.")] = False,
    episode_start: Annotated[Optional[int], typer.Option("--episode-start", min=0, help="First episode of this shard of a larger exploration (with --episode-count; join shards with 'afford merge').")] = None,
    episode_count: Annotated[Optional[int], typer.Option("--episode-count", min=1, help="Episodes in this shard, from --episode-start (0 by default).")] = None,
    json: Json = False,
) -> None:
    """Let the robot explore: random worlds, its behaviours, what happened recorded (Algorithm 5 or 1).

    Finished episodes are journaled in OUTPUT.partial/ as they arrive: after Ctrl-C, SIGTERM
    or a crash, run the same command with --resume to finish, to the same bytes."""
    if episodes is not None and interactions is not None:
        raise typer.BadParameter("give --episodes or --interactions, not both")
    if episode_count is not None and (episodes is not None or interactions is not None):
        raise typer.BadParameter("--episode-count sizes a shard; it does not go with --episodes or --interactions")
    if episode_start is not None and episode_count is None:
        raise typer.BadParameter("--episode-start begins a shard: give its size with --episode-count")
    if scheduler is not None and backend is not Backend.dask:
        raise typer.BadParameter("--scheduler is a Dask cluster's address: it needs --backend dask")
    if episode_count is not None:
        episodes = episode_count
    if episodes is None and interactions is None:
        episodes = 100
    for name, value in (("--size-min", size_min), ("--size-max", size_max)):
        if value is not None and not (0.02 <= value <= 0.6):
            raise typer.BadParameter(f"{name} must be between 0.02 and 0.6 m, got {value}")
    if size_min is not None and size_max is not None and size_min > size_max:
        raise typer.BadParameter(f"--size-min ({size_min}) is larger than --size-max ({size_max})")
    check_output(output)
    out = Output(json, stdout_busy=writes_stdout(output))
    sc = make_scene(scene, size_min=size_min, size_max=size_max, max_steps=max_steps, grid=grid, layers=layers)
    data, result = record(out, sc, output, episodes=episodes, interactions=interactions, seed=seed,
                          workers=workers, episode_start=episode_start or 0, backend=backend.value,
                          scheduler=scheduler, resume=resume)

    def render(console):
        console.print(f"[bold]explored[/] {result['interactions']} interactions in {result['episodes']} episodes, "
                      f"{result['seconds']:.1f} s ({result['interactions_per_second']}/s) -> {output}")
        console.print("features: " + ", ".join(f"{ch} {n}" for ch, n in result["channels"].items())
                      + f" ({result['n_features']} in all); labels {result['label_source']}")
        if data.result is not None:
            render_result_rates(console, result["result_rates"])
        else:
            render_outcome_table(console, outcome_table(data))

    out.result(result, render)
