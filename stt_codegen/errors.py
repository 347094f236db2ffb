"""The toolkit's own exceptions.

Every error a user can cause with a spec file or a command-line argument is a
:class:`SpecError` (or a subclass of :class:`SttError`): the command line turns
it into one line on standard error and exit code 2, without a traceback.
"""

from __future__ import annotations


class SttError(Exception):
    """Base class of every error the toolkit raises on purpose."""


class SpecError(SttError, ValueError):
    """A spec file (or a value derived from it) is invalid.

    Parameters
    ----------
    field : str
        Dotted name of the offending field, e.g. ``"initial.state"`` or
        ``"obstacles[2].lower"``; ``""`` for the file as a whole.
    reason : str
        Why the value is rejected, in words.
    """

    def __init__(self, field: str, reason: str) -> None:
        self.field = field
        self.reason = reason
        super().__init__(f"{field}: {reason}" if field else reason)


class DesignError(SttError):
    """No spatiotemporal tube satisfying the checks could be designed for a spec."""
