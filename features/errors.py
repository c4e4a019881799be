"""afford's own error types, defined where every package can reach them.

:class:`DataError` is bad input or data a user can fix (a layout, a goal, too few
interactions, an option a scene lacks): the command line reports it in one sentence and
exits 1. Anything else that escapes is a bug, and surfaces as one.
"""

from __future__ import annotations

__all__ = ["DataError", "NameNotFound"]


class DataError(ValueError):
    """Input or data that cannot be used, said in one sentence."""


class NameNotFound(DataError, KeyError):
    """A name (a feature, a channel, a scene) that is not there."""

    def __str__(self) -> str:  # KeyError quotes its message otherwise
        return str(self.args[0]) if self.args else ""
