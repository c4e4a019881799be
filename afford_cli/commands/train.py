"""``afford train``: per-behaviour predictors with calibrated probabilities; writes a ``model``."""

from __future__ import annotations

from typing import Annotated, Optional

import typer
from rich.table import Table

from afford.artifacts import check_output, writes_stdout
from afford.options import InputPath, Json, KernelOption, OutputPath, Seed
from afford.output import Output


def train(
    path: InputPath,
    output: OutputPath,
    kernel: KernelOption = None,
    folds: Annotated[Optional[int], typer.Option("--folds", min=2, max=10, help="Cross-validation folds that choose C (and gamma) and report accuracy; by default the scene's (5 for the traverse scenes, 3 at the table).")] = None,
    search_rows: Annotated[Optional[int], typer.Option("--search-rows", min=10, help="Choose C and gamma by cross-validation on a stratified sample of at most this many rows per behaviour, then calibrate and fit on every row (libsvm's cost grows with the square of the rows); by default the scene's (grasp: 3000), else every row.")] = None,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Train each behaviour's predictor of its labels (effect categories or given results), probabilities calibrated."""
    from afford.api import train as run

    check_output(output, [path])
    out = Output(json, stdout_busy=writes_stdout(output))
    with out.progress("training predictors", None) as update:
        result = run(path, output, kernel=kernel.value if kernel is not None else None, folds=folds, seed=seed,
                     search_rows=search_rows, progress=update)

    def render(console):
        learner = "random forest" if result["kernel"] == "forest" else f"{result['kernel']} SVM"
        table = Table(title=f"trained predictors ({learner})")
        forest = result["kernel"] == "forest"
        for col in ("behaviour", "categories", "features", *(("smallest leaf",) if forest else ("C", "gamma")),
                    "out-of-bag accuracy" if forest else "cross-validated accuracy"):
            table.add_column(col, no_wrap=True)
        for name, b in result["behaviors"].items():
            p = b["best_params"]
            # a behaviour with one effect has no machine: it is certain of that effect
            grid = ([f"{p['min_samples_leaf']:g}" if "min_samples_leaf" in p else "-"] if forest else
                    [f"{p['C']}" if "C" in p else "-", f"{p.get('gamma', '-'):.3g}" if "gamma" in p else "-"])
            table.add_row(name, str(b["n_categories"]), str(b["n_features"]), *grid, f"{100 * b['cv_accuracy']:.1f}%")
        console.print(table)
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
