"""The errors flexarm raises on purpose, all in one place.

Every check of user input raises :class:`InvalidValueError` (a ``ValueError``)
or :class:`InvalidTypeError` (a ``TypeError``), with a message that names the
parameter, what was expected and what was given. Both derive from
:class:`FlexarmError`, so the command line can tell bad input (exit status 2,
one line) from a bug (a ``ValueError`` raised anywhere else is not caught and
shows its traceback). A problem in a file (a scenario, a sweep) is a
:class:`ConfigFileError` naming the file and the dotted key.

One error is defined beside what it carries: :class:`flexarm.sim.results.SimulationError`
(a diverged run, with its partial :class:`~flexarm.sim.results.SimulationResult`).

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

from pathlib import Path

__all__ = [
    "CalibrationError",
    "Cancelled",
    "ClusterError",
    "ConfigError",
    "ConfigFileError",
    "ConfigTypeError",
    "FlexarmError",
    "InvalidTypeError",
    "InvalidValueError",
    "KeyPathError",
    "OutputDirectoryError",
    "ScenarioError",
    "SweepError",
    "SweepInterrupted",
    "SweepTypeError",
    "UnstableStepError",
]


class FlexarmError(Exception):
    """Base class of the errors flexarm raises on purpose."""


class InvalidValueError(FlexarmError, ValueError):
    """A parameter or an input has a wrong value or shape (or a data file cannot be
    read as asked)."""


class InvalidTypeError(FlexarmError, TypeError):
    """A parameter or an input has a wrong type."""


class UnstableStepError(InvalidValueError):
    """An integration step beyond the stability bound of the dynamics it integrates
    (the message names the steps that work)."""


class Cancelled(FlexarmError):
    """A run was stopped before its end because its ``stop`` flag was set (e.g. by
    a batch that was interrupted); nothing of it was kept."""


class ClusterError(FlexarmError, RuntimeError):
    """A task failed on a Dask cluster for another reason than its runs (a worker lost
    too often, a worker without flexarm). The runs finished before are in the journal."""


class SweepInterrupted(KeyboardInterrupt):
    """A sweep stopped by Ctrl-C; its journal holds every run finished before.

    Attributes
    ----------
    finished, total : int
        Distinct runs finished (journal included) and in the sweep.
    journal : Path or None
        The journal (None without an output directory).
    """

    def __init__(self, finished: int, total: int, journal: Path | None):
        self.finished, self.total, self.journal = finished, total, journal
        super().__init__(f"{finished} of {total} runs finished")


class OutputDirectoryError(InvalidValueError):
    """An output directory that cannot take a sweep's results."""


# ------------------------------------------------------------------ files
class ConfigFileError(FlexarmError):
    """A file (a scenario, a sweep) that cannot be used as it is.

    Its message is one line, ``"{source}: {key}: {reason}"`` (without the key where
    the problem is the whole file or the key is in the reason).

    Attributes
    ----------
    source : str
        Where the file came from (its name).
    key : str or None
        Dotted key of the offending entry (``"trajectory.side"``,
        ``"arm.links[1].length"``, ``"monte_carlo.n"``), the section, or None for the
        whole file.
    reason : str
        The problem, without the source and key.
    """

    def __init__(self, source: str, key: str | None, reason: str, *, show_key: bool = True):
        self.source = source
        self.key = key
        self.reason = reason
        where = f"{key}: " if key and show_key else ""
        super().__init__(f"{source}: {where}{reason}")


class ConfigError(ConfigFileError, InvalidValueError):
    """A wrong value in a file."""


class ConfigTypeError(ConfigFileError, InvalidTypeError):
    """An entry of the wrong type in a file."""


class KeyPathError(InvalidValueError):
    """A dotted key that cannot be set in a file's tables (``reason`` says why); the
    readers report it as their file's error, naming the file."""

    def __init__(self, key: str, reason: str):
        self.key, self.reason = key, reason
        super().__init__(f"{key}: {reason}")


class ScenarioError(ConfigError):
    """A scenario that cannot be built (a wrong value, or an entry of the wrong type)."""


class SweepError(ConfigError):
    """A sweep that cannot be run: a wrong value in the file or the mapping."""


class SweepTypeError(ConfigTypeError):
    """A sweep that cannot be run: an entry of the wrong type."""


class CalibrationError(ConfigError):
    """A calibration that cannot be run: a wrong value in its configuration, or a
    record that cannot be read as the configuration says."""
