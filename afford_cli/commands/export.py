"""``afford export``: interactions as a table (CSV or Parquet) for pandas and friends."""

from __future__ import annotations

from typing import Annotated, Optional

import typer

from afford.artifacts import check_not_input, check_output, write_artifact, writes_stdout
from afford.options import InputPath, Json
from afford.output import Output


def export(
    path: InputPath,
    output: Annotated[str, typer.Option("--output", "-o", help="Where to write the table; '-' for stdout.")],
    format: Annotated[Optional[str], typer.Option("--format", "-f", help="csv or parquet; by default the output's suffix, else csv.")] = None,
    json: Json = False,
) -> None:
    """Write interactions (features by name, behaviour, parameters, labels, categories, ground truth) as a table."""
    from afford.export import check_extras, export_bytes, format_for, to_frame

    fmt = format_for(output, format)
    check_extras(fmt)
    check_not_input(output, [path])
    if not (output == "-" and fmt == "csv"):  # CSV is text: the terminal may have it
        check_output(output)
    frame = to_frame(path)
    write_artifact(output, export_bytes(frame, fmt))
    result = {"output": output, "format": fmt, "rows": int(frame.shape[0]), "columns": int(frame.shape[1])}
    Output(json, stdout_busy=writes_stdout(output)).result(
        result, lambda console: console.print(f"exported {result['rows']} rows x {result['columns']} columns "
                                              f"({fmt}) -> {output}"))
