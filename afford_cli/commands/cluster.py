"""``afford cluster``: discover effect categories per behaviour; writes an ``effects`` artefact."""

from __future__ import annotations

import time
from enum import Enum
from typing import Annotated, Optional

import typer

from afford.artifacts import artifact_bytes, check_output, write_artifact, writes_stdout
from afford.errors import AffordError
from afford.learning import effects_members, read_rows
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
    from afford.learn.affordances import discover_effects

    if k is not None and method is not Method.kmeans:
        raise typer.BadParameter("--k goes with --method kmeans")
    check_output(output)
    out = Output(json, stdout_busy=writes_stdout(output))
    art, data = read_rows(path)
    if not data.has_after:
        raise AffordError(f"{art.source} records nothing after its behaviours, so it has no effects to cluster; "
                          f"its labels are given ({'/'.join(data.result_names)}): run select-features or train on it directly")
    start = time.perf_counter()
    with out.progress("clustering effects (behaviours)", len(data.behaviors)) as update:
        models, labels = discover_effects(data, method=method.value, k_max=kmax, k=k, prune=prune.value,
                                          min_fraction=min_fraction, seed=seed, progress=update)
    settings = {"method": method.value, "k_max": kmax, "k": k, "prune": prune.value, "min_fraction": min_fraction}
    arrays, meta, blobs = effects_members(data, labels, models, settings)
    write_artifact(output, artifact_bytes("effects", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    result = {"output": output, "seconds": round(time.perf_counter() - start, 3),
              "behaviors": {name: {"n_categories": s["n_categories"], "pruned_rows": s["pruned_rows"],
                                   "categories": s["categories"]} for name, s in meta["effects"].items()}}

    def render(console):
        from afford.reports import render_categories

        for name, s in meta["effects"].items():
            render_categories(console, name, s["categories"], [(ch, [data.schema.names[i] for i in idx]) for ch, idx in data.schema.channel_groups()])
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
