"""The ``afford`` command line: wires the commands; each lives in ``afford.commands``.

Exit codes: 0 success, 1 a runtime or data error (one sentence on stderr, ``error: ...``;
``AFFORD_DEBUG=1`` shows the traceback), 2 a usage error.
"""

from __future__ import annotations

import functools
import os
import sys
from typing import Annotated, Callable

import typer

from afford.commands import (
    cluster, demo, emulate, evaluate, explore, export, inspect, merge, navigate, pddl, plan, predict, scenes,
    select_features, train,
)
from afford.errors import AffordError, Interrupted
from afford.features.errors import DataError

app = typer.Typer(
    name="afford",
    help="Learn what objects afford by playing with them in simulation (after Ugur's thesis).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)


def _show_version(value: bool) -> None:
    if value:
        from afford import __version__

        typer.echo(f"afford {__version__}")
        raise typer.Exit()


@app.callback()
def _options(
    version: Annotated[bool, typer.Option("--version", callback=_show_version, is_eager=True,
                                          help="Print afford's version and exit.")] = False,
) -> None:
    """Learn what objects afford by playing with them in simulation (after Ugur's thesis)."""


def _guarded(command: Callable) -> Callable:
    """Known failures become ``error: <one sentence>`` on stderr and exit code 1."""

    @functools.wraps(command)
    def run(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except (AffordError, DataError, OSError) as exc:
            # afford's own errors (and the operating system's) are the user's to fix; anything
            # else is a bug in afford and surfaces as one
            if os.environ.get("AFFORD_DEBUG") == "1":
                raise
            message = str(exc)
            sys.stderr.write(f"error: {message}\n")
            raise typer.Exit(1) from None
        except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: outputs are written whole or not at all
            message = str(exc) if isinstance(exc, Interrupted) else "interrupted; the output being written was discarded"
            sys.stderr.write(f"\nerror: {message}\n")
            raise typer.Exit(130) from None

    return run


for _name, _command in (("scenes", scenes.scenes), ("explore", explore.explore), ("cluster", cluster.cluster),
                        ("select-features", select_features.select_features), ("train", train.train),
                        ("evaluate", evaluate.evaluate), ("predict", predict.predict),
                        ("plan", plan.plan), ("emulate", emulate.emulate), ("navigate", navigate.navigate), ("pddl", pddl.pddl),
                        ("merge", merge.merge), ("inspect", inspect.inspect), ("export", export.export), ("demo", demo.demo)):
    app.command(_name)(_guarded(_command))


def _terminate(signum, frame):  # noqa: ARG001
    raise KeyboardInterrupt  # SIGTERM is an interruption like Ctrl-C: temp files go, exit 130


def main(argv: list[str] | None = None) -> None:
    """Console entry point."""
    import signal

    signal.signal(signal.SIGTERM, _terminate)
    try:
        app(args=argv)
    except KeyboardInterrupt:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)
    except BrokenPipeError:  # a pipeline reader went away: not our error to report
        sys.exit(1)
    finally:
        # the command has ended and its exit code is set: a Ctrl-C or SIGTERM that lands
        # while the interpreter shuts down (joining the progress bar's thread, say) would
        # otherwise kill the process by the signal and hide that code
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        signal.signal(signal.SIGTERM, signal.SIG_IGN)


if __name__ == "__main__":  # pragma: no cover
    main()
