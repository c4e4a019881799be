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
from afford.interrupt import install

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


def _interruption(exc: BaseException | None) -> KeyboardInterrupt | None:
    """The Ctrl-C or SIGTERM that caused ``exc``, if one did. An interruption that lands
    inside an import of a compiled module comes out as ``ImportError: initialization
    failed`` caused by it (seen with open3d), and one inside a library's clean-up may come
    out as another error."""
    seen = set()
    while exc is not None and id(exc) not in seen:
        if isinstance(exc, KeyboardInterrupt):
            return exc
        seen.add(id(exc))
        exc = exc.__cause__ or exc.__context__
    return None


#: Set once an interruption has been reported, so that :func:`main` does not report it twice.
_reported: list[bool] = [False]


def _interrupted(exc: BaseException) -> typer.Exit:
    message = str(exc) if isinstance(exc, Interrupted) else "interrupted; the output being written was discarded"
    sys.stderr.write(f"\nerror: {message}\n")
    _reported[0] = True
    return typer.Exit(130)


def _guarded(command: Callable) -> Callable:
    """Known failures become ``error: <one sentence>`` on stderr and exit code 1; an
    interruption (Ctrl-C, SIGTERM), and any error it caused, exits with 130."""

    @functools.wraps(command)
    def run(*args, **kwargs):
        try:
            return command(*args, **kwargs)
        except KeyboardInterrupt as exc:  # Ctrl-C or SIGTERM: outputs are written whole or not at all
            raise _interrupted(exc) from None
        except Exception as exc:
            cause = _interruption(exc)
            if cause is not None:
                raise _interrupted(cause) from None
            if not isinstance(exc, (AffordError, DataError, OSError)):
                raise  # anything else is a bug in afford and surfaces as one
            # afford's own errors (and the operating system's) are the user's to fix
            if os.environ.get("AFFORD_DEBUG") == "1":
                raise
            sys.stderr.write(f"error: {exc}\n")
            raise typer.Exit(1) from None

    return run


for _name, _command in (("scenes", scenes.scenes), ("explore", explore.explore), ("cluster", cluster.cluster),
                        ("select-features", select_features.select_features), ("train", train.train),
                        ("evaluate", evaluate.evaluate), ("predict", predict.predict),
                        ("plan", plan.plan), ("emulate", emulate.emulate), ("navigate", navigate.navigate), ("pddl", pddl.pddl),
                        ("merge", merge.merge), ("inspect", inspect.inspect), ("export", export.export), ("demo", demo.demo)):
    app.command(_name)(_guarded(_command))


def main(argv: list[str] | None = None) -> None:
    """The command line (the console entry point, :func:`afford.interrupt.main`, installs the
    interruption handlers before it imports this module, then calls this)."""
    import signal

    install()  # again, for a caller of this function: the console entry point did it first
    try:
        app(args=argv)
    except KeyboardInterrupt:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)
    except SystemExit as exc:
        if exc.code == 130 and not _reported[0]:  # interrupted outside a command (typer's own 130)
            sys.stderr.write("\nerror: interrupted\n")
        raise
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
