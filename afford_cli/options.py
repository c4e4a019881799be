"""Options shared by every command, defined once so help reads the same everywhere."""

from __future__ import annotations

from typing import Annotated

import typer

__all__ = ["Seed", "Workers", "Json", "OutputPath", "InputPath", "SceneName", "Alternatives"]

Seed = Annotated[int, typer.Option("--seed", "-s", min=0, help="Random seed; the same seed gives the same arrays whatever --workers is.")]
Workers = Annotated[int, typer.Option("--workers", "-w", min=1, max=64, help="Parallel worker processes.")]
Json = Annotated[bool, typer.Option("--json", help="Print one JSON object instead of the human report.")]
OutputPath = Annotated[str, typer.Option("--output", "-o", help="Where to write the artefact; '-' for stdout.")]
InputPath = Annotated[str, typer.Argument(help="An afford artefact file, or '-' for stdin.", metavar="PATH|-")]
SceneName = Annotated[str, typer.Option("--scene", help="A registered scene (see 'afford scenes').")]
Alternatives = Annotated[int, typer.Option(
    "--alternatives", min=1, max=10,
    help="Search this many of the most probable plans and take the one most likely to reach the goal with monitoring "
         "(each replan too); the others are reported. 1: the most probable plan, assessed alone.")]
