"""One object decides where things go: stdout carries exactly one thing.

That thing is the human report, or ``--json`` (one JSON object), or the artefact bytes when
``-o -``. Progress bars, warnings and errors go to stderr; when stdout carries the artefact,
the report (human or JSON) goes to stderr too, and with ``--json`` no progress bar is drawn
there, so stderr holds one JSON object (or an error).
"""

from __future__ import annotations

import json
import os
import sys
from contextlib import contextmanager
from typing import Any, Callable, Iterator

from rich.console import Console
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn, TimeRemainingColumn

__all__ = ["Output"]


class Output:
    def __init__(self, json_mode: bool = False, stdout_busy: bool = False):
        self.json_mode = json_mode
        self.stdout_busy = stdout_busy
        self.err = Console(stderr=True, highlight=False)
        self.report = Console(stderr=stdout_busy, highlight=False, soft_wrap=False)
        if not self.report.is_terminal and "COLUMNS" not in os.environ:
            # Reports piped to a file or another program are not squeezed into 80 columns.
            self.report.width = 120

    def result(self, data: dict[str, Any], render: Callable[[Console], None]) -> None:
        """Emit the command's result: JSON, or the human rendering."""
        if self.json_mode:
            text = json.dumps(data, indent=1, sort_keys=False, default=_jsonable)
            stream = sys.stderr if self.stdout_busy else sys.stdout
            stream.write(text + "\n")
            stream.flush()
        else:
            render(self.report)

    def warn(self, message: str) -> None:
        self.err.print(f"[yellow]warning:[/] {message}")

    def info(self, message: str) -> None:
        self.err.print(message, soft_wrap=True, markup=False, highlight=False)

    @contextmanager
    def progress(self, description: str, total: int | None, lazy: bool = False) -> Iterator[Callable[..., None]]:
        """A rich progress bar on stderr; yields ``update(completed, total=None)`` (a total
        given later, by the work itself, replaces an unknown one). ``lazy``: the bar appears
        at the first update, so checks that fail before any work leave stderr one sentence."""
        columns = (TextColumn("{task.description}"), BarColumn(), MofNCompleteColumn(),
                   TimeElapsedColumn(), TextColumn("eta"), TimeRemainingColumn())
        # with --json while stdout carries the artefact, stderr carries the JSON alone
        bar = Progress(*columns, console=self.err, transient=False, disable=self.json_mode and self.stdout_busy)
        task = None

        def update(done, new_total=None):
            nonlocal task
            if task is None:
                bar.start()
                task = bar.add_task(description, total=total)
            bar.update(task, completed=done, **({"total": new_total} if new_total is not None else {}))

        if not lazy:
            update(0)
        try:
            yield update
        finally:
            if task is not None:
                bar.stop()


def _jsonable(value: Any) -> Any:
    try:
        import numpy as np

        if isinstance(value, np.generic):
            return value.item()
        if isinstance(value, np.ndarray):
            return value.tolist()
    except ImportError:  # pragma: no cover
        pass
    raise TypeError(f"not JSON serialisable: {type(value).__name__}")
