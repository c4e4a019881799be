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
from afford.plots import PlotDir, plot_directory
from afford.output import Output


class Backend(str, Enum):
    loky = "loky"
    dask = "dask"


class Strategy(str, Enum):
    random = "random"
    margin = "margin"
    entropy = "entropy"
    committee = "committee"


def explore_online_command(output: str, scene: str, strategy: str, *, seed: int, workers: int, grid, layers, room,
                           clutter=None, tau: float,
                           bootstrap: int, candidates: int, threshold: float, budget, test, plots, json: bool,
                           size_min=None, size_max=None, others: dict) -> None:
    """``explore --strategy``: curiosity-driven exploration (:mod:`afford.curiosity`)."""
    from afford.artifacts import artifact_bytes, write_artifact
    from afford.curiosity import explore_online, online_members
    from afford.learning import read_rows

    given = [k for k, v in others.items() if v is not None]
    if given:
        raise typer.BadParameter(f"{given[0]} does not go with --strategy: a curiosity-driven exploration tries "
                                 "--candidates situations once each, on this machine")
    check_output(output)
    plot_dir = plot_directory(plots) if plots is not None else None
    out = Output(json, stdout_busy=writes_stdout(output))
    sc = make_scene(scene, grid=grid, layers=layers, room=room, clutter=clutter, size_min=size_min, size_max=size_max)
    test_data = read_rows(test, ("interactions",))[1] if test is not None else None
    start = time.perf_counter()
    with out.progress(f"curious about {sc.name}", candidates, lazy=True) as update:
        def progress(stage, done, total):  # scanning the candidates, then each behaviour learned
            update(done, total)

        data, tried, report = explore_online(sc, strategy, candidates=candidates, bootstrap=bootstrap, tau=tau,
                                             threshold=threshold, budget=budget, test=test_data, seed=seed,
                                             workers=workers, progress=progress)
    arrays, meta = online_members(data, tried, report)
    write_artifact(output, artifact_bytes("interactions", arrays, meta, seed=seed))
    result = {**summary(data, time.perf_counter() - start), "output": output, **report}
    if plot_dir is not None and "curve" in report:
        from afford.plots import curve_figure

        result["plots"] = [curve_figure(plot_dir / "learning-curve.png", report["curve"], strategy)]

    def render(console):
        console.print(f"[bold]curious[/] ({strategy}): of {candidates} candidates, tried per behaviour: "
                      + ", ".join(f"{n} {b['tried']}" for n, b in report["behaviors"].items())
                      + f"; {len(data)} interactions -> {output}")
        if "curve" in report:
            last = {}
            for c in report["curve"]:
                last[c["behavior"]] = c
            console.print("test accuracy at the end: " + ", ".join(
                f"{n} {100 * c['accuracy']:.1f}% ({c['interactions']} tried)" for n, c in last.items()))

    out.result(result, render)
    if plot_dir is not None and result.get("plots"):
        from afford.plots import written

        out.info(written(result["plots"]))


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
    room: Annotated[Optional[int], typer.Option("--room", min=0, help="Which room (its seed) the robot explores (traverse-room: chapter 6 learns in one room and tests in another; 0 by default).")] = None,
    clutter: Annotated[Optional[int], typer.Option("--clutter", min=0, max=80, help="Loose objects in the room (traverse-room: 30 by default; with --size-min/--size-max, a harder room of more, smaller things).")] = None,
    shapes: Annotated[Optional[str], typer.Option("--shapes", metavar="S1,S2", help="The shapes the scene's objects are drawn from (traverse-one, thesis 5.6.4.1: box, cylinder, lying-cylinder, sphere; all four by default).")] = None,
    furniture: Annotated[Optional[str], typer.Option("--furniture", help="The piece in front of the robot (traverse-furniture, thesis 5.6.4.2): wooden-table, iron-table or chair.")] = None,
    backend: Annotated[Backend, typer.Option("--backend", help="Where episodes run: loky (processes on this machine) or dask (a LocalCluster of --workers on 127.0.0.1, or the cluster at --scheduler; needs the optional dask extra). The same --seed gives the same bytes on either.")] = Backend.loky,
    scheduler: Annotated[Optional[str], typer.Option("--scheduler", metavar="ADDRESS", help="A running Dask scheduler (tcp://HOST:PORT) to explore on, with --backend dask; its workers need afford installed.")] = None,
    resume: Annotated[bool, typer.Option("--resume", help="Continue the interrupted run whose finished episodes are journaled in OUTPUT.partial/ (same options); starts afresh if there is none.")] = False,
    episode_start: Annotated[Optional[int], typer.Option("--episode-start", min=0, help="First episode of this shard of a larger exploration (with --episode-count; join shards with 'afford merge').")] = None,
    episode_count: Annotated[Optional[int], typer.Option("--episode-count", min=1, help="Episodes in this shard, from --episode-start (0 by default).")] = None,
    strategy: Annotated[Optional[Strategy], typer.Option("--strategy", help="Curiosity-driven exploration (thesis chapter 6; scenes whose results are given, or whose effect categories are discovered from the bootstrap, as at the table): look at --candidates situations and act only where the learner finds them interesting: random (all), margin (the thesis: SVM output within --tau), entropy (calibrated probabilities, --threshold or --budget), committee (a bootstrap ensemble disagrees).")] = None,
    tau: Annotated[float, typer.Option("--tau", min=0.0, help="margin: try a candidate whose SVM output lies within this of the boundary (the thesis's 0.5).")] = 0.5,
    bootstrap: Annotated[int, typer.Option("--bootstrap", min=2, help="Candidates tried first, all of them, to choose the features (ReliefF, once), discover the effect categories (scenes that discover them; at least 10) and fit the first SVM (the thesis's 25).")] = 25,
    candidates: Annotated[int, typer.Option("--candidates", min=2, help="Candidate situations in the stream: environments, or objects on the table (the thesis's 3000).")] = 3000,
    threshold: Annotated[float, typer.Option("--threshold", min=0.0, max=1.0, help="entropy: try a candidate whose predicted result or category has at least this entropy, in units of its largest (bits for two results).")] = 0.7,
    budget: Annotated[Optional[int], typer.Option("--budget", min=1, help="entropy: try about this many candidates per behaviour, the most uncertain (instead of --threshold).")] = None,
    test: Annotated[Optional[str], typer.Option("--test", metavar="DATA", help="Interactions of the same scene to score the learner on as it goes: --json holds the learning curve.")] = None,
    plots: PlotDir = None,
    json: Json = False,
) -> None:
    """Let the robot explore: random worlds, its behaviours, what happened recorded (Algorithm 5 or 1).

    Finished episodes are journaled in OUTPUT.partial/ as they arrive: after Ctrl-C, SIGTERM
    or a crash, run the same command with --resume to finish, to the same bytes. With
    --strategy the robot explores out of curiosity instead (thesis chapter 6)."""
    if strategy is not None:
        return explore_online_command(output, scene, strategy.value, seed=seed, workers=workers, grid=grid, layers=layers, room=room,
                                      clutter=clutter,
                                      tau=tau, bootstrap=bootstrap, candidates=candidates, threshold=threshold,
                                      budget=budget, test=test, plots=plots, json=json, size_min=size_min, size_max=size_max,
                                      others={"--episodes": episodes, "--interactions": interactions,
                                              "--max-steps": max_steps,
                                              "--resume": resume or None, "--episode-start": episode_start,
                                              "--episode-count": episode_count, "--scheduler": scheduler,
                                              "--backend": None if backend is Backend.loky else backend.value})
    for name, value in (("--bootstrap", bootstrap != 25 or None), ("--candidates", candidates != 3000 or None),
                        ("--tau", tau != 0.5 or None), ("--threshold", threshold != 0.7 or None), ("--budget", budget),
                        ("--test", test), ("--plots", plots)):
        if value is not None:
            raise typer.BadParameter(f"{name} goes with --strategy (curiosity-driven exploration)")
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
    sc = make_scene(scene, size_min=size_min, size_max=size_max, max_steps=max_steps, grid=grid, layers=layers, room=room,
                    clutter=clutter,
                    shapes=shapes, furniture=furniture)
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
