"""The errors of a sweep file, and the checks that raise them.

Every problem with a sweep file is reported in one line that starts with the
file and names the key, as scenario files do
(:class:`~flexarm.sim.scenario_schema.ScenarioError`)::

    sweep.toml: monte_carlo.n: must be an integer >= 1. Got 0 instead.
    sweep.toml: grid: unknown key 'sensor.noise_stdd' (JointSensor takes noise_std, ...)

:class:`SweepError` is an :class:`~flexarm.errors.InvalidValueError` (a wrong
value) and :class:`SweepTypeError` an :class:`~flexarm.errors.InvalidTypeError`
(a wrong type); the command line turns both into exit status 2.

This module needs no compiled code: the command line checks a sweep file
before anything heavy is imported.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NoReturn

from ..errors import InvalidTypeError, InvalidValueError

__all__ = ["SweepError", "SweepReader", "SweepTypeError", "Value"]

Value = str | int | float | bool | list["Value"] | dict[str, "Value"]
"""A value a TOML file can hold (dates and times excepted): what a swept key takes."""


def _message(source: str, key: str | None, reason: str) -> str:
    return f"{source}: {key}: {reason}" if key else f"{source}: {reason}"


class SweepError(InvalidValueError):
    """A sweep that cannot be run: a wrong value in the file or the mapping.

    Attributes
    ----------
    source : str
        Where the sweep came from (the file name).
    key : str or None
        Dotted key of the offending entry (``"monte_carlo.n"``,
        ``"grid.sensor.noise_std"``), or None for the whole file.
    reason : str
        The problem, without the source and key.
    """

    def __init__(self, source: str, key: str | None, reason: str):
        self.source, self.key, self.reason = source, key, reason
        super().__init__(_message(source, key, reason))


class SweepTypeError(InvalidTypeError):
    """A sweep that cannot be run: an entry of the wrong type (attributes as
    :class:`SweepError`)."""

    def __init__(self, source: str, key: str | None, reason: str):
        self.source, self.key, self.reason = source, key, reason
        super().__init__(_message(source, key, reason))


class SweepReader:
    """Checks the entries of one sweep file and reports against its source.

    Parameters
    ----------
    source : str
        Named at the start of every message (the file name).
    """

    def __init__(self, source: str):
        self.source = source

    def fail(self, key: str | None, reason: str) -> NoReturn:
        """Raise :class:`SweepError`."""
        raise SweepError(self.source, key, reason)

    def fail_type(self, key: str | None, reason: str) -> NoReturn:
        """Raise :class:`SweepTypeError`."""
        raise SweepTypeError(self.source, key, reason)

    def table(self, value: object, key: str) -> Mapping[str, object]:
        """``value`` if it is a table, else a type error naming ``key``."""
        if not isinstance(value, Mapping):
            self.fail_type(key, f"must be a table ([{key}]). Got {value!r} instead.")
        return value

    def keys(self, table: Mapping[str, object], key: str, allowed: tuple[str, ...]) -> None:
        """Refuse any key of ``table`` not in ``allowed``."""
        for name in table:
            if name not in allowed:
                where = f"{key}.{name}" if key else name
                self.fail(
                    None,
                    f"unknown key '{where}' ({key or 'a sweep file'} takes {', '.join(allowed)})",
                )

    def integer(self, value: object, key: str, minimum: int) -> int:
        """``value`` as an int ``>= minimum``."""
        if isinstance(value, bool) or not isinstance(value, int):
            self.fail_type(key, f"must be an integer >= {minimum}. Got {value!r} instead.")
        if value < minimum:
            self.fail(key, f"must be an integer >= {minimum}. Got {value!r} instead.")
        return int(value)

    def real(self, value: object, key: str) -> float:
        """``value`` as a finite float (an int is accepted)."""
        if isinstance(value, bool) or not isinstance(value, int | float):
            self.fail_type(key, f"must be a real number. Got {value!r} instead.")
        x = float(value)
        if not math.isfinite(x):
            self.fail(key, f"must be finite. Got {value!r} instead.")
        return x

    def string(self, value: object, key: str) -> str:
        """``value`` if it is a non-empty string."""
        if not isinstance(value, str) or not value:
            self.fail_type(key, f"must be a non-empty string. Got {value!r} instead.")
        return value

    def value(self, value: object, key: str) -> Value:
        """``value`` as a plain TOML value (NumPy scalars to Python, tuples to lists).

        Dates and times and other objects are refused: a run is a scenario
        mapping that must travel as JSON (to the journal, to a cluster).
        """
        if isinstance(value, bool | str):
            return value
        if isinstance(value, int | float):
            return value
        item = getattr(value, "item", None)  # a NumPy scalar
        if callable(item) and type(value).__module__ == "numpy" and getattr(value, "ndim", 1) == 0:
            return self.value(item(), key)
        if isinstance(value, list | tuple):
            return [self.value(v, f"{key}[{k}]") for k, v in enumerate(value)]
        if isinstance(value, Mapping):
            out: dict[str, Value] = {}
            for name, v in value.items():
                if not isinstance(name, str):
                    self.fail_type(key, f"keys must be strings. Got {name!r} instead.")
                out[name] = self.value(v, f"{key}.{name}")
            return out
        self.fail_type(
            key,
            "must be a number, a string, a boolean, an array or a table. "
            f"Got {type(value).__name__} {value!r} instead.",
        )
