"""``afford train``: per-behaviour predictors with calibrated probabilities; writes a ``model``."""

from __future__ import annotations

import time
from typing import Annotated, Optional

import typer
from rich.table import Table

from afford.artifacts import artifact_bytes, check_output, write_artifact, writes_stdout
from afford.learning import learner_settings, model_members, read_effects, read_rows, read_selection
from afford.options import InputPath, Json, KernelOption, OutputPath, Seed
from afford.output import Output


def train(
    path: InputPath,
    output: OutputPath,
    kernel: KernelOption = None,
    folds: Annotated[Optional[int], typer.Option("--folds", min=2, max=10, help="Cross-validation folds that choose C (and gamma) and report accuracy; by default the scene's (5 for the traverse scenes, 3 at the table).")] = None,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Train each behaviour's predictor of its labels (effect categories or given results), probabilities calibrated."""
    from afford.learn.affordances import train_known, train_predictors

    check_output(output)
    out = Output(json, stdout_busy=writes_stdout(output))
    art, data = read_rows(path, ("interactions", "effects", "features"))
    labels, effects = read_effects(art, data)
    selected = read_selection(art, data)
    kernel_name, n_folds = learner_settings(art, data, kernel.value if kernel is not None else None, folds)
    start = time.perf_counter()
    with out.progress(f"training predictors ({kernel_name} SVM)", len(data.behaviors)) as update:
        predictors = train_predictors(data, labels, selected, kernel=kernel_name, folds=n_folds, seed=seed,
                                      progress=update)
    known = train_known(data, labels, seed=seed) if effects is not None else None
    settings = {"kernel": kernel_name, "folds": n_folds, "selection": art.kind}
    arrays, meta, blobs = model_members(art, data, labels, effects, selected, predictors, settings, known)
    write_artifact(output, artifact_bytes("model", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    result = {"output": output, "seconds": round(time.perf_counter() - start, 3),
              "behaviors": {n: {"cv_accuracy": cv["cv_accuracy"], "best_params": cv["best_params"],
                                "n_categories": len(meta["categories"][n])} for n, cv in meta["cv"].items()}}

    def render(console):
        table = Table(title="trained predictors")
        for col in ("behaviour", "categories", "features", "C", "gamma", "cross-validated accuracy"):
            table.add_column(col, no_wrap=True)
        for name, cv in meta["cv"].items():
            p = cv["best_params"]
            table.add_row(name, str(len(meta["categories"][name])), str(len(selected[name])), f"{p.get('C')}",
                          f"{p.get('gamma', '-'):.3g}" if "gamma" in p else "-", f"{100 * cv['cv_accuracy']:.1f}%")
        console.print(table)
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
