"""``afford select-features``: which object features matter, per behaviour; writes ``features``."""

from __future__ import annotations

import time
from enum import Enum
from typing import Annotated, Optional

import typer
from rich.table import Table

from afford.artifacts import artifact_bytes, check_output, write_artifact, writes_stdout
from afford.learning import features_members, learner_settings, read_effects, read_rows
from afford.options import InputPath, Json, KernelOption, OutputPath, Seed
from afford.output import Output


class Method(str, Enum):
    relieff = "relieff"
    forward = "forward"
    backward = "backward"


def select_features(
    path: InputPath,
    output: OutputPath,
    method: Annotated[Method, typer.Option(help="ReliefF (Algorithm 3), forward selection (sequentialfs) or backward elimination (schemata search).")] = Method.relieff,
    top: Annotated[Optional[int], typer.Option("--top", min=1, help="Keep this many features, best first.")] = None,
    group_channels: Annotated[bool, typer.Option("--group-channels", help="Wrappers move each 18-bin histogram as one unit.")] = False,
    kernel: KernelOption = None,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Rank the entity features by relevance to each behaviour's labels (effect categories, or given results)."""
    from afford.learn.affordances import rank_features

    check_output(output)
    out = Output(json, stdout_busy=writes_stdout(output))
    art, data = read_rows(path, ("interactions", "effects", "features"))
    labels, _ = read_effects(art, data)
    kernel_name, _ = learner_settings(art, data, kernel.value if kernel is not None else None)
    start = time.perf_counter()
    with out.progress(f"selecting features ({method.value})", len(data.behaviors)) as update:
        relevance = rank_features(data, labels, method=method.value, top=top, seed=seed,
                                  group_channels=group_channels, kernel=kernel_name, progress=update)
    settings = {"method": method.value, "top": top, "group_channels": group_channels, "kernel": kernel_name}
    arrays, meta, blobs = features_members(art, data, relevance, settings)
    write_artifact(output, artifact_bytes("features", arrays, meta, parents=[art.parent_ref()], seed=seed, blobs=blobs))
    result = {"output": output, "seconds": round(time.perf_counter() - start, 3),
              "behaviors": {n: {"selected": r["selected"]} for n, r in meta["relevance"].items()}}

    def render(console):
        table = Table(title=f"relevant features ({method.value})")
        table.add_column("behaviour", no_wrap=True)
        table.add_column("n", justify="right")
        table.add_column("features, most relevant first")
        for name, r in meta["relevance"].items():
            table.add_row(name, str(len(r["selected"])), ", ".join(r["selected"]))
        console.print(table)
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
