"""``afford merge``: join shards of one exploration into one ``interactions`` artefact."""

from __future__ import annotations

from typing import Annotated

import typer

from afford.options import Json, OutputPath
from afford.output import Output


def merge(
    paths: Annotated[list[str], typer.Argument(help="Shards written by 'afford explore --episode-start S --episode-count C'.", metavar="SHARD...")],
    output: OutputPath,
    json: Json = False,
) -> None:
    """Join shards of one exploration (same scene, schema and seed; episodes neither overlapping
    nor missing) into the interactions a one-shot run gives."""
    from afford.api import merge as run
    from afford.artifacts import check_output, writes_stdout

    check_output(output, paths)
    result = run(paths, output)
    Output(json, stdout_busy=writes_stdout(output)).result(
        result, lambda console: console.print(
            f"merged {result['shards']} shard{'' if result['shards'] == 1 else 's'}: {result['interactions']} interactions of episodes "
            f"{result['episodes'][0]}-{result['episodes'][1] - 1} (seed {result['seed']}) -> {output}"))
