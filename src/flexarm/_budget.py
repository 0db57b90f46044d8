"""Limits on what one request may cost, checked before anything is allocated.

A request that would need more memory than :func:`memory_limit` or more time
than :func:`time_limit` is refused with :class:`~flexarm.errors.InvalidValueError`
stating what it would take, what to change, and how to raise the limit. The
limits are the user's: the environment variables ``FLEXARM_MAX_MEMORY`` (bytes,
or with a unit: ``512M``, ``32G``) and ``FLEXARM_MAX_TIME`` (seconds, or
``90m``, ``12h``). ``0`` or ``inf`` switches a limit off.

Defaults: half of this machine's physical memory, and one hour.
"""

from __future__ import annotations

import math
import os
import re

from .errors import InvalidValueError

__all__ = [
    "MEMORY_ENV",
    "TIME_ENV",
    "check_memory",
    "check_time",
    "format_bytes",
    "format_seconds",
    "memory_limit",
    "time_limit",
]

MEMORY_ENV = "FLEXARM_MAX_MEMORY"
TIME_ENV = "FLEXARM_MAX_TIME"
_DEFAULT_TIME = 3600.0
_BYTE_UNITS = {"": 1, "k": 2**10, "m": 2**20, "g": 2**30, "t": 2**40}
_TIME_UNITS = {"": 1.0, "s": 1.0, "m": 60.0, "h": 3600.0, "d": 86400.0}


def _physical_memory() -> float:
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, ValueError, OSError):  # pragma: no cover - not POSIX
        return 8.0 * 2**30


def _parse(text: str, units: dict[str, float] | dict[str, int], env: str) -> float:
    match = re.fullmatch(r"\s*([0-9.eE+]+|inf)\s*([a-zA-Z]?)[bB]?\s*", text)
    unit = match.group(2).lower() if match else ""
    try:
        if match is None or unit not in units:
            raise ValueError
        value = float(match.group(1)) * units[unit]
    except ValueError:
        raise InvalidValueError(
            f"The environment variable {env} must be a number with an optional unit "
            f"({', '.join(u for u in units if u)}). Got {text!r} instead."
        ) from None
    if math.isnan(value) or value < 0:
        raise InvalidValueError(f"The environment variable {env} must be >= 0. Got {text!r}.")
    return math.inf if value == 0 else value


def memory_limit() -> float:
    """The most memory one request may need, bytes (``inf``: no limit)."""
    text = os.environ.get(MEMORY_ENV)
    return 0.5 * _physical_memory() if text is None else _parse(text, _BYTE_UNITS, MEMORY_ENV)


def time_limit() -> float:
    """The longest one request may be expected to run, s (``inf``: no limit)."""
    text = os.environ.get(TIME_ENV)
    return _DEFAULT_TIME if text is None else _parse(text, _TIME_UNITS, TIME_ENV)


def format_bytes(n: float) -> str:
    """``1.5 GB``-style text (powers of 1024)."""
    for unit, size in (("TB", 2**40), ("GB", 2**30), ("MB", 2**20), ("kB", 2**10)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} B"


def format_seconds(s: float) -> str:
    """``3.2 h``-style text."""
    for unit, size in (("years", 3.15576e7), ("days", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if s >= size:
            return f"{s / size:.3g} {unit}"
    return f"{s:.3g} s"


def check_memory(nbytes: float, what: str, owner: str, remedy: str) -> None:
    """Refuse ``what`` (e.g. "this run") if it needs more than :func:`memory_limit`.

    ``remedy`` says what to change (a sentence without the final period).
    """
    limit = memory_limit()
    if nbytes > limit:
        raise InvalidValueError(
            f"The request to {owner} ({what}) would need about {format_bytes(nbytes)} of "
            f"memory, more than the limit of {format_bytes(limit)}. {remedy}; or raise the "
            "limit with the "
            f"environment variable {MEMORY_ENV} (e.g. {MEMORY_ENV}=64G, 0 for none)."
        )


def check_time(seconds: float, what: str, owner: str, remedy: str) -> None:
    """Refuse ``what`` if it is expected to take longer than :func:`time_limit`."""
    limit = time_limit()
    if seconds > limit:
        raise InvalidValueError(
            f"The request to {owner} ({what}) would take about {format_seconds(seconds)} on "
            f"this machine, longer than the limit of {format_seconds(limit)}. {remedy}; or "
            f"raise the limit with the environment variable {TIME_ENV} (e.g. {TIME_ENV}=12h, "
            "0 for none)."
        )
