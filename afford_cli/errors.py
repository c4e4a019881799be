"""The one exception type the CLI turns into ``error: <sentence>`` and exit code 1."""


class AffordError(Exception):
    """A user-facing failure: bad input, a refused file, an impossible request."""
