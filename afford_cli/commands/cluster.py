"""``afford cluster``: discover effect categories per behaviour; writes an ``effects`` artefact."""

from __future__ import annotations

from contextlib import contextmanager
from enum import Enum
from typing import Annotated, Optional

import typer

from afford.artifacts import check_output, writes_stdout
from afford.errors import AffordError
from afford.options import InputPath, Json, OutputPath, Seed
from afford.output import Output


class Method(str, Enum):
    hierarchical = "hierarchical"
    kmeans = "kmeans"


class Prune(str, Enum):
    frequency = "frequency"
    predictability = "predictability"


def parse_k(values: list[str] | None) -> dict[str, int] | None:
    """``--k 4 --k lift=2`` as ``{"*": 4, "lift": 2}`` (a usage error, one sentence, if malformed)."""
    if not values:
        return None
    out: dict[str, int] = {}
    for v in values:
        name, _, number = v.rpartition("=")
        try:
            n = int(number)
        except ValueError:
            raise typer.BadParameter(f"--k takes K or BEHAVIOUR=K with K a whole number, got {v!r}") from None
        if not 2 <= n <= 50:
            raise typer.BadParameter(f"--k must be 2-50 clusters, got {n}")
        key = name.strip() or "*"
        if key in out:
            raise typer.BadParameter(f"--k is given twice for {'every behaviour' if key == '*' else key}; give it once")
        out[key] = n
    return out


@contextmanager
def _cli_wording(prune: "Prune"):
    """The learner's advice in the command line's words (its options, not Python names)."""
    from afford.learn.effects import NoCategoryLeft  # the learner loads with the command, not at start-up

    try:
        yield
    except NoCategoryLeft:
        advice = ("lower --min-fraction" if prune is Prune.frequency else
                  "cluster with --prune frequency (the features told no category apart well enough)")
        raise AffordError(f"no effect category survived pruning; {advice}, or collect more interactions") from None


def cluster(
    path: InputPath,
    output: OutputPath,
    method: Annotated[Optional[Method], typer.Option(help="Channel-wise X-means with a Cartesian product (chapter 8), or one-level k-means (chapter 7). Default: the scene's own (crane-lift: kmeans), else hierarchical.")] = None,
    kmax: Annotated[Optional[int], typer.Option("--kmax", min=1, max=20, help="Most categories X-means may find in one channel. Default: the scene's own (grasp: 4), else 5.")] = None,
    k: Annotated[Optional[list[str]], typer.Option("--k", help="Clusters of k-means: K for every behaviour, or BEHAVIOUR=K for one (repeat the option).")] = None,
    prune: Annotated[Prune, typer.Option(help="Drop rare categories (chapter 8) or unpredictable ones (Algorithm 7).")] = Prune.frequency,
    min_fraction: Annotated[Optional[float], typer.Option("--min-fraction", min=0.0, max=0.5, help="Frequency pruning: smallest share a category must hold.  [default: 0.03]")] = None,
    channels: Annotated[Optional[str], typer.Option("--channels", help="Comma-separated effect channels that form categories (hierarchical); the others still shape the prototypes. Default: the scene's own (grasp: visibility,cp,touch, as tables 9.1-9.2), else all.")] = None,
    seed: Seed = 0,
    json: Json = False,
) -> None:
    """Discover effect categories per behaviour, without labels (thesis 8.4.1, Algorithm 7)."""
    from afford.api import cluster as run

    ks = parse_k(k)
    if ks is not None and method is Method.hierarchical:
        raise typer.BadParameter("--k goes with --method kmeans")
    if kmax is not None and method is Method.kmeans:
        raise typer.BadParameter("--kmax bounds X-means (--method hierarchical); k-means takes --k")
    if min_fraction is not None and prune is Prune.predictability:
        raise typer.BadParameter("--min-fraction goes with --prune frequency; predictability pruning drops "
                                 "the categories the features cannot tell apart, whatever their share")
    check_output(output, [path])
    out = Output(json, stdout_busy=writes_stdout(output))
    with out.progress("clustering effects (behaviours)", None, lazy=True) as update, _cli_wording(prune):
        result = run(path, output, method=None if method is None else method.value, k_max=kmax, k=ks, prune=prune.value,
                     min_fraction=0.03 if min_fraction is None else min_fraction, seed=seed, progress=update,
                     channels=None if channels is None else [c.strip() for c in channels.split(",") if c.strip()])

    def render(console):
        from afford.reports import render_categories

        why = "rare kinds" if prune is Prune.frequency else "unpredictable kinds"
        for name, s in result["behaviors"].items():
            render_categories(console, name, s["categories"], [(ch, names) for ch, names in result["channels"]])
            total = s["pruned_rows"] + sum(int(c["count"]) for c in s["categories"])
            console.print(f"{name}: {s['pruned_rows']} of {total} interactions dropped ({why})")
        console.print(f"-> {output} ({result['seconds']:.1f} s)")

    out.result(result, render)
