"""The errors flexarm raises on purpose.

Every check of user input raises :class:`InvalidValueError` (a ``ValueError``)
or :class:`InvalidTypeError` (a ``TypeError``), with a message that names the
parameter, what was expected and what was given. Both derive from
:class:`FlexarmError`, so the command line can tell bad input (exit status 2,
one line) from a bug (a ``ValueError`` raised anywhere else is not caught and
shows its traceback).

Examples
--------
>>> from flexarm.model.link import Link
>>> try:
...     Link(-1.0, 1.0, 1.0)
... except ValueError as err:          # still a ValueError for callers who catch that
...     print(type(err).__name__)
InvalidValueError
"""

from __future__ import annotations

__all__ = ["Cancelled", "FlexarmError", "InvalidTypeError", "InvalidValueError"]


class FlexarmError(Exception):
    """Base class of the errors flexarm raises on purpose."""


class InvalidValueError(FlexarmError, ValueError):
    """A parameter or an input has a wrong value or shape (or a data file cannot be
    read as asked)."""


class InvalidTypeError(FlexarmError, TypeError):
    """A parameter or an input has a wrong type."""


class Cancelled(FlexarmError):
    """A run was stopped before its end because its ``stop`` flag was set (e.g. by
    a batch that was interrupted); nothing of it was kept."""
