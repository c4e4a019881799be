"""The command line as the tests drive it: run a command in-process, expect success or one clean failure."""

from __future__ import annotations

from typer.testing import CliRunner

from afford.app import app

runner = CliRunner()


def ok(args):
    """Run ``afford ARGS``; it must exit 0."""
    result = runner.invoke(app, args)
    assert result.exit_code == 0, (args, result.output)
    return result


def fails(args, code=1):
    """Run ``afford ARGS``; it must exit ``code`` without a traceback. Returns its output."""
    result = runner.invoke(app, args)
    assert result.exit_code == code, (args, result.output)
    assert "Traceback" not in result.output
    return result.output
