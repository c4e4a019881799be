"""The ``afford`` command line: wires the commands; each lives in ``afford_cli.commands``.

Exit codes: 0 success, 1 a runtime or data error (one sentence on stderr, ``error: ...``;
``AFFORD_DEBUG=1`` shows the traceback), 2 a usage error.
"""

from __future__ import annotations

import os
import sys
import warnings

import typer

from afford_cli.commands import demo, explore, inspect, scenes
from afford_cli.errors import AffordError

app = typer.Typer(
    name="afford",
    help="Learn what objects afford by playing with them in simulation (after Ugur's thesis).",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
app.command("scenes")(scenes.scenes)
app.command("explore")(explore.explore)
app.command("inspect")(inspect.inspect)
app.command("demo")(demo.demo)


def _quiet_libraries() -> None:
    warnings.filterwarnings("ignore", message="Failed to find system libvulkan")


def main(argv: list[str] | None = None) -> None:
    """Console entry point: run the app, turn known failures into exit code 1."""
    _quiet_libraries()
    debug = os.environ.get("AFFORD_DEBUG") == "1"
    try:
        app(args=argv, standalone_mode=True)
    except SystemExit:
        raise
    except (AffordError, ValueError, KeyError, OSError) as exc:
        if debug:
            raise
        message = str(exc.args[0]) if isinstance(exc, KeyError) and exc.args else str(exc)
        sys.stderr.write(f"error: {message}\n")
        sys.exit(1)
    except KeyboardInterrupt:
        sys.stderr.write("error: interrupted\n")
        sys.exit(130)


if __name__ == "__main__":  # pragma: no cover
    main()
