"""Ctrl-C and SIGTERM as one interruption (exit 130), set up before anything heavy is imported.

This module imports only the standard library, so the ``afford`` command installs its
handler first, then imports the commands (open3d, SAPIEN, scikit-learn: about a second). A
SIGTERM in that second used to kill the process by the signal; now it waits for the import
in progress (see :func:`terminate`) and ends the command like any other interruption.
"""

from __future__ import annotations

import contextlib
import os
import signal
import sys
import threading

__all__ = ["install", "terminate", "uninterrupted", "main"]

#: How long an interruption that landed inside an import waits before it is raised again.
RETRY_SECONDS = 0.05


def _importing(frame) -> bool:
    """Is ``frame`` (where a signal landed) inside an import?"""
    while frame is not None:
        if frame.f_code.co_filename.startswith("<frozen importlib"):
            return True
        frame = frame.f_back
    return False


def terminate(signum, frame):
    """Ctrl-C and SIGTERM are one interruption: temp files go, exit 130. One that lands inside
    an import waits until the import is done (it is raised again 50 ms on): raised inside a
    compiled module's initialisation (open3d's, seen), it broke the interpreter, which then
    ended with an ImportError's traceback, with exit code 1, or killed by SIGINT."""
    if _importing(frame):
        retry = threading.Timer(RETRY_SECONDS, os.kill, (os.getpid(), signum))
        retry.daemon = True
        retry.start()
        return
    raise KeyboardInterrupt


def install() -> None:
    """SIGTERM, and SIGINT unless the shell made this process ignore it (a job sent to the
    background by a non-interactive shell), raise :func:`terminate`'s interruption."""
    signal.signal(signal.SIGTERM, terminate)
    if signal.getsignal(signal.SIGINT) in (signal.default_int_handler, terminate):
        signal.signal(signal.SIGINT, terminate)


@contextlib.contextmanager
def uninterrupted():
    """A few steps that must all happen or none (a probe file made and removed): Ctrl-C and
    SIGTERM are held until they are done, then delivered."""
    if not hasattr(signal, "pthread_sigmask"):  # not POSIX: nothing to hold them with
        yield
        return
    held = {signal.SIGINT, signal.SIGTERM}
    before = signal.pthread_sigmask(signal.SIG_BLOCK, held)
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, before)


def main(argv: list[str] | None = None) -> None:
    """The ``afford`` console entry point: the handlers first, then the commands."""
    install()
    try:
        from afford.app import main as run

        run(argv)
    except KeyboardInterrupt:  # landed while the commands were being imported, or as one ended
        sys.stderr.write("\nerror: interrupted\n")
        sys.exit(130)
