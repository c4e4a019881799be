"""``afford navigate``: drive the mobile robot through a room with its learned affordances (thesis 5.6.5)."""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Optional

import typer

from afford.learning import load_model
from afford.options import Json, SceneName
from afford.output import Output
from afford.plots import PlotFile, check_plot_file
from afford.scenes_io import make_scene


class Controller(str, Enum):
    aggressive = "aggressive"
    cautious = "cautious"
    random = "random"


def navigate(
    model: Annotated[str, typer.Argument(help="A model of the mobile robot's moves (learned on a traverse scene).", metavar="MODEL")],
    scene: SceneName = "room",
    controller: Annotated[Controller, typer.Option("--controller", help="aggressive: the first afforded move, go-forward first (Figure 5.9a); cautious: the mean direction of the most neighbouring afforded moves, only if more than one (5.9b); random: any move, blind (the baseline).")] = Controller.aggressive,
    seed: Annotated[int, typer.Option("--seed", "-s", min=0, help="Which room (unless --room) and where in it the robot starts; range noise.")] = 0,
    room: Annotated[Optional[int], typer.Option("--room", min=0, help="Which room (its seed); --seed by default.")] = None,
    steps: Annotated[int, typer.Option("--steps", min=1, max=100000, help="Most scans (each followed by a move, or by a look around when nothing is afforded).")] = 100,
    threshold: Annotated[float, typer.Option("--threshold", min=0.0, max=1.0, help="A move is afforded when its chance of success is at least this.")] = 0.5,
    plot: PlotFile = None,
    json: Json = False,
) -> None:
    """Drive the robot through a room: at every step scan, predict each move, let the controller choose, move on (thesis 5.6.5)."""
    from afford.navigation import draw_navigation, navigate as run

    check_plot_file(plot)
    loaded = load_model(model)
    sc = make_scene(scene)
    if "room" in sc.options:
        sc = make_scene(scene, room=seed if room is None else room)
    elif room is not None:
        raise typer.BadParameter(f"--room does not apply to scene {scene!r}")
    out = Output(json)
    result = run(loaded, sc, controller.value, seed=seed, steps=steps, threshold=threshold)
    if plot is not None:
        result["plot"] = draw_navigation(plot, sc, result)

    def render(console):
        per_m = "-" if result["failed_per_metre"] is None else f"{result['failed_per_metre']:.2f}"
        console.print(f"[bold]{result['controller']}[/] in {result['scene']} (room {result['room']}): "
                      f"{result['distance_m']:.2f} m in {result['moves']} moves, {result['failed_moves']} failed "
                      f"({per_m} per metre), {result['looks']} looks around; "
                      + (f"stuck: {result['stuck_because']}" if result["stuck"] else f"not stuck after {result['steps']} steps"))

    out.result(result, render)
