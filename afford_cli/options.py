"""Options shared by every command, defined once so help reads the same everywhere."""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Optional

import typer

__all__ = ["Seed", "Workers", "Json", "OutputPath", "InputPath", "SceneName", "ModelScene", "Alternatives", "SceneSeed", "Objects",
           "Layout", "MaxDepth", "MaxNodes", "MaxReplans", "check_scene_source", "Kernel", "KernelOption",
           "EffectModel", "Effects"]

Seed = Annotated[int, typer.Option("--seed", "-s", min=0, help="Random seed: the same seed gives the same arrays (whatever --workers is, where a command has workers).")]
Workers = Annotated[int, typer.Option("--workers", "-w", min=1, max=64, help="Parallel worker processes.")]
Json = Annotated[bool, typer.Option("--json", help="Print one JSON object instead of the human report.")]
OutputPath = Annotated[str, typer.Option("--output", "-o", help="Where to write the artefact; '-' for stdout.")]
InputPath = Annotated[str, typer.Argument(help="An afford artefact file, or '-' for stdin.", metavar="PATH|-")]
SceneName = Annotated[str, typer.Option("--scene", help="A registered scene (see 'afford scenes').")]
ModelScene = Annotated[Optional[str], typer.Option(
    "--scene", help="A registered scene (see 'afford scenes'); default: the scene the model was learned in.")]
Alternatives = Annotated[int, typer.Option(
    "--alternatives", min=1, max=10,
    help="Search this many of the most probable plans and take the one most likely to reach the goal with monitoring "
         "(each replan too); the others are reported. 1: the most probable plan, assessed alone.")]

class Kernel(str, Enum):
    rbf = "rbf"
    linear = "linear"
    forest = "forest"


KernelOption = Annotated[Optional[Kernel], typer.Option(
    "--kernel", help="The learner: an SVM's kernel, or 'forest', a random forest (ours, not the thesis's; it needs no "
                     "feature selection); by default the scene's (linear for the traverse scenes, as in thesis chapter 5; "
                     "RBF at the table).")]


class EffectModel(str, Enum):
    members = "members"
    prototype = "prototype"


Effects = Annotated[EffectModel, typer.Option(
    "--effects", help="How a category's effect on an object is predicted: from the category's members most like it "
                      "(members), or the category's mean for every object (prototype, the thesis's model).")]


class AlphaRule(str, Enum):
    group = "group"
    probability = "probability"
    grid = "grid"


AlphaRuleOpt = Annotated[AlphaRule, typer.Option(
    "--alpha-rule", help="How a behaviour's parameter (chapter 9's approach angle) is chosen: the mean of the largest "
                         "group of grid angles leading to each next state (group, thesis 9.5), the angle that makes "
                         "each next state most probable (probability), or every point of a 5-point grid (grid).")]


# -- where a command acts: a drawn scene or a pinned layout, and the planner's limits ------
SceneSeed = Annotated[Optional[int], typer.Option("--seed", "-s", min=0, help="Draw a random scene from this seed.")]
Objects = Annotated[Optional[int], typer.Option("--objects", min=1, max=6, help="Objects in a drawn scene (scenes that have objects to act on).")]
Layout = Annotated[Optional[str], typer.Option("--layout", help="A TOML layout file that pins the scene.")]
MaxDepth = Annotated[int, typer.Option("--max-depth", min=1, max=8, help="Longest plan.")]
MaxNodes = Annotated[int, typer.Option("--max-nodes", min=1, help="Most search nodes to expand.")]
MaxReplans = Annotated[int, typer.Option("--max-replans", min=0, max=20, help="Most replans after surprises.")]
BlindRollouts = Annotated[int, typer.Option(
    "--blind-rollouts", min=0, max=100_000,
    help="Also judge the plan run blind in this many imagined worlds, each step's whole effect drawn from one of "
         "the nearest members (0: not).")]


def check_scene_source(layout: Optional[str], seed: Optional[int], **drawn) -> None:
    """``--layout`` pins the scene; ``--seed`` (with the drawing options, given when set) draws one; not both."""
    given = (["--seed"] if seed is not None else []) + [f"--{k.replace('_', '-')}" for k, v in drawn.items() if v is not None]
    if layout is not None and given:
        raise typer.BadParameter(f"--layout pins the scene; it does not go with {' or '.join(given)}")
    if layout is None and seed is None:
        raise typer.BadParameter("give --layout FILE, or --seed S to draw a random scene")
