"""The exception types the CLI turns into ``error: <sentence>``: exit code 1, or 130 when interrupted."""


class AffordError(Exception):
    """A user-facing failure: bad input, a refused file, an impossible request."""


class Interrupted(KeyboardInterrupt):
    """Ctrl-C or SIGTERM stopped the work; the message says what was kept and how to go on."""
