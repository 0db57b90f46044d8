"""The reader of sweep files: the shared file reader with the sweep's error classes.

Every problem with a sweep file is reported in one line that starts with the
file and names the key, as scenario files do::

    sweep.toml: monte_carlo.n: must be an integer >= 1. Got 0 instead.
    sweep.toml: unknown key 'sensor.noise_stdd' (JointSensor takes noise_std, ...)

:class:`~flexarm.errors.SweepError` is a wrong value and
:class:`~flexarm.errors.SweepTypeError` an entry of the wrong type; the command
line turns both into exit status 2.

This module needs no compiled code: the command line checks a sweep file
before anything heavy is imported.
"""

from __future__ import annotations

from .._config import ConfigReader, TomlValue
from ..errors import SweepError, SweepTypeError

__all__ = ["SweepError", "SweepReader", "SweepTypeError", "Value"]

Value = TomlValue
"""A value a TOML file can hold (dates and times excepted): what a swept key takes."""


class SweepReader(ConfigReader):
    """Checks the entries of one sweep file and reports against its source.

    Parameters
    ----------
    source : str
        Named at the start of every message (the file name).
    """

    def __init__(self, source: str):
        super().__init__(source, SweepError, SweepTypeError, whole="a sweep file")
