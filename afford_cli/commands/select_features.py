"""``afford select-features``: which object features matter, per behaviour; writes ``features``."""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Optional

import typer
from rich.table import Table

from afford.artifacts import check_output, writes_stdout
from afford.options import InputPath, Json, KernelOption, OutputPath, Seed
from afford.output import Output


class Score(str, Enum):
    accuracy = "accuracy"
    log_loss = "log-loss"


class Method(str, Enum):
    relieff = "relieff"
    forward = "forward"
    backward = "backward"


def select_features(
    path: InputPath,
    output: OutputPath,
    method: Annotated[Method, typer.Option(help="ReliefF (Algorithm 3), forward selection (sequentialfs) or backward elimination (schemata search).")] = Method.relieff,
    top: Annotated[Optional[int], typer.Option("--top", min=1, help="Keep this many features, best first (default: ReliefF's ranking cut where the cross-validated score (--score) is within one standard error of the best; the wrappers' own stopping rule).")] = None,
    group_channels: Annotated[bool, typer.Option("--group-channels", help="Wrappers move each 18-bin histogram as one unit.")] = False,
    kernel: KernelOption = None,
    score: Annotated[Optional[Score], typer.Option(help="What ReliefF's ranking cut scores: the SVM's cross-validated accuracy, or its calibrated probabilities' log loss (a feature that makes a rare effect likelier without making it the likeliest counts). Default: the scene's own (grasp: log-loss), else accuracy.")] = None,
    search_rows: Annotated[Optional[int], typer.Option("--search-rows", min=10, help="Cut ReliefF's ranking by cross-validating on a stratified sample of at most this many rows per behaviour (the ranking reads every row); by default the scene's (grasp: 3000), else every row. Not with --top or a wrapper, which make no cut.")] = None,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Rank the entity features by relevance to each behaviour's labels (effect categories, or given results)."""
    from afford.api import select_features as run

    check_output(output, [path])
    out = Output(json, stdout_busy=writes_stdout(output))
    with out.progress(f"selecting features ({method.value})", None) as update:
        result = run(path, output, method=method.value, top=top, group_channels=group_channels,
                     kernel=kernel.value if kernel is not None else None,
                     score=None if score is None else score.value.replace("-", "_"), seed=seed,
                     search_rows=search_rows, progress=update,
                     warn=out.warn)

    def render(console):
        table = Table(title=f"relevant features ({method.value})")
        table.add_column("behaviour", no_wrap=True)
        table.add_column("n", justify="right")
        table.add_column("features, most relevant first")
        for name, r in result["behaviors"].items():
            # a parameter was a candidate too; it goes into the predictor in any case
            ranks = [f"{p} ranked {v['rank']}" for p, v in r.get("parameters", {}).items()]
            table.add_row(name, str(len(r["selected"])), ", ".join(r["selected"]) + (f" ({'; '.join(ranks)})" if ranks else ""))
        console.print(table)
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
