"""``afford cluster``: discover effect categories per behaviour; writes an ``effects`` artefact."""

from __future__ import annotations

from enum import Enum
from typing import Annotated, Optional

import typer

from afford.artifacts import check_output, writes_stdout
from afford.options import InputPath, Json, OutputPath, Seed
from afford.output import Output


class Method(str, Enum):
    hierarchical = "hierarchical"
    kmeans = "kmeans"


class Prune(str, Enum):
    frequency = "frequency"
    predictability = "predictability"


def cluster(
    path: InputPath,
    output: OutputPath,
    method: Annotated[Method, typer.Option(help="Channel-wise X-means with a Cartesian product (chapter 8), or one-level k-means (chapter 7).")] = Method.hierarchical,
    kmax: Annotated[int, typer.Option("--kmax", min=1, max=20, help="Most categories X-means may find in one channel.")] = 5,
    k: Annotated[Optional[int], typer.Option("--k", min=2, max=50, help="Clusters of --method kmeans.")] = None,
    prune: Annotated[Prune, typer.Option(help="Drop rare categories (chapter 8) or unpredictable ones (Algorithm 7).")] = Prune.frequency,
    min_fraction: Annotated[float, typer.Option("--min-fraction", min=0.0, max=0.5, help="Frequency pruning: smallest share a category must hold.")] = 0.03,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Discover effect categories per behaviour, without labels (thesis 8.4.1, Algorithm 7)."""
    from afford.api import cluster as run

    if k is not None and method is not Method.kmeans:
        raise typer.BadParameter("--k goes with --method kmeans")
    check_output(output)
    out = Output(json, stdout_busy=writes_stdout(output))
    with out.progress("clustering effects (behaviours)", None) as update:
        result = run(path, output, method=method.value, k_max=kmax, k=k, prune=prune.value,
                     min_fraction=min_fraction, seed=seed, progress=update)

    def render(console):
        from afford.reports import render_categories

        for name, s in result["behaviors"].items():
            render_categories(console, name, s["categories"], [(ch, names) for ch, names in result["channels"]])
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
