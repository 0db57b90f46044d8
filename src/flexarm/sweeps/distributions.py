"""The distributions of a Monte Carlo sweep, and their reproducible draws.

A ``[monte_carlo]`` entry is a table naming its distribution and parameters::

    "controller.zeta" = { distribution = "uniform", low = 0.5, high = 0.9 }
    "sensor.noise_std" = { distribution = "loguniform", low = 1e-5, high = 1e-3 }
    "controller.kp" = { distribution = "normal", mean = 150.0, std = 10.0 }
    "sensor.kind" = { distribution = "choice", values = ["joint", "tip"], weights = [3, 1] }
    "simulation.seed" = { distribution = "integers", low = 0, high = 1000000 }

Each key draws from its own generator, ``numpy.random.default_rng`` of a
:class:`numpy.random.SeedSequence` made of the sweep's seed and the key's name
(:func:`key_rng`): the draws of one key do not depend on the other keys, on
their order in the file, nor on where or in which order the runs are done.

Examples
--------
>>> Uniform(0.5, 0.9).draw(key_rng(0, "controller.zeta"), 3)
[0.6405, 0.7505, 0.5374]
>>> Choice(("joint", "tip")).draw(key_rng(0, "sensor.kind"), 4)
['tip', 'joint', 'tip', 'tip']
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .reader import SweepReader, Value

__all__ = [
    "DISTRIBUTIONS",
    "Choice",
    "Distribution",
    "Integers",
    "LogUniform",
    "Normal",
    "Uniform",
    "distribution_from_table",
    "key_rng",
]


def key_rng(seed: int, key: str) -> np.random.Generator:
    """The generator of one swept key: the sweep's ``seed`` and the key's name.

    The name enters as a spawn key of 64 bits of its SHA-256 (stable across
    processes and machines; Python's ``hash`` is not).
    """
    code = int.from_bytes(hashlib.sha256(key.encode()).digest()[:8], "little")
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(code,)))


@dataclass(frozen=True)
class Uniform:
    """Uniform on ``[low, high)``.

    Parameters
    ----------
    low, high : float
        The bounds, in the unit of the swept key (``low < high``).
    """

    low: float
    high: float
    name: ClassVar[str] = "uniform"

    def draw(self, rng: np.random.Generator, n: int) -> list[Value]:
        """``n`` draws from ``rng``, as Python floats."""
        return [float(x) for x in rng.uniform(self.low, self.high, size=n)]


@dataclass(frozen=True)
class LogUniform:
    """Log-uniform on ``[low, high)``: ``exp`` of a uniform draw on ``[log low, log high)``.

    Parameters
    ----------
    low, high : float
        The bounds, in the unit of the swept key (``0 < low < high``).
    """

    low: float
    high: float
    name: ClassVar[str] = "loguniform"

    def draw(self, rng: np.random.Generator, n: int) -> list[Value]:
        """``n`` draws from ``rng``, as Python floats."""
        u = rng.uniform(math.log(self.low), math.log(self.high), size=n)
        return [float(x) for x in np.exp(u)]


@dataclass(frozen=True)
class Normal:
    """Normal of mean ``mean`` and standard deviation ``std``.

    Parameters
    ----------
    mean : float
        In the unit of the swept key.
    std : float
        In the unit of the swept key (>= 0).
    """

    mean: float
    std: float
    name: ClassVar[str] = "normal"

    def draw(self, rng: np.random.Generator, n: int) -> list[Value]:
        """``n`` draws from ``rng``, as Python floats."""
        return [float(x) for x in rng.normal(self.mean, self.std, size=n)]


@dataclass(frozen=True)
class Integers:
    """Integers uniform on ``low, low + 1, ..., high - 1`` (``high`` excluded, as NumPy).

    Parameters
    ----------
    low, high : int
        ``low < high``. For seeds: ``low = 0, high = 2**31``.
    """

    low: int
    high: int
    name: ClassVar[str] = "integers"

    def draw(self, rng: np.random.Generator, n: int) -> list[Value]:
        """``n`` draws from ``rng``, as Python ints."""
        return [int(x) for x in rng.integers(self.low, self.high, size=n)]


@dataclass(frozen=True)
class Choice:
    """One of ``values``, with probabilities proportional to ``weights``.

    Parameters
    ----------
    values : tuple
        The candidates (any TOML values: numbers, strings, arrays, tables).
    weights : tuple of float, optional
        One per value, >= 0, not all 0 (default: equal).
    """

    values: tuple[Value, ...]
    weights: tuple[float, ...] | None = None
    name: ClassVar[str] = "choice"

    def draw(self, rng: np.random.Generator, n: int) -> list[Value]:
        """``n`` draws from ``rng`` (the values themselves, not copies)."""
        p = None
        if self.weights is not None:
            w = np.asarray(self.weights, dtype=float)
            p = w / w.sum()
        picks = rng.choice(len(self.values), size=n, p=p)
        return [self.values[int(k)] for k in picks]


Distribution = Uniform | LogUniform | Normal | Integers | Choice
"""Any of the distributions a ``[monte_carlo]`` entry can name."""

DISTRIBUTIONS: dict[str, tuple[str, ...]] = {
    "uniform": ("low", "high"),
    "loguniform": ("low", "high"),
    "normal": ("mean", "std"),
    "integers": ("low", "high"),
    "choice": ("values",),
}
"""Each distribution's name and required parameters (``choice`` also takes ``weights``)."""


def distribution_from_table(table: Mapping[str, object], key: str, r: SweepReader) -> Distribution:
    """The distribution a ``[monte_carlo]`` entry describes, checked.

    Parameters
    ----------
    table : mapping
        ``{distribution = NAME, PARAMETER = VALUE, ...}``.
    key : str
        The entry's dotted key in the file (``"monte_carlo.controller.zeta"``),
        named in every message.
    r : SweepReader
        Reports against the file.

    Raises
    ------
    SweepError, SweepTypeError
        An unknown distribution, a missing or unknown parameter, a bad value.
    """
    name = table.get("distribution")
    if not isinstance(name, str) or name not in DISTRIBUTIONS:
        r.fail(
            f"{key}.distribution",
            f"must be one of {tuple(DISTRIBUTIONS)}. Got {name!r} instead.",
        )
    needed = DISTRIBUTIONS[name]
    allowed = ("distribution", *needed, *(("weights",) if name == "choice" else ()))
    for param in table:
        if param not in allowed:
            r.fail(
                None,
                f"unknown key '{key}.{param}' ({name} takes {', '.join(allowed[1:])})",
            )
    for param in needed:
        if param not in table:
            r.fail(key, f"missing key '{key}.{param}' ({name} needs {', '.join(needed)})")
    if name == "choice":
        return _choice(table, key, r)
    if name == "integers":
        lo = _int(table["low"], f"{key}.low", r)
        hi = _int(table["high"], f"{key}.high", r)
        if not lo < hi:
            r.fail(f"{key}.high", f"must be > low ({lo}; high is excluded). Got {hi} instead.")
        return Integers(lo, hi)
    a, b = (r.real(table[p], f"{key}.{p}") for p in needed)
    if name == "normal":
        if b < 0:
            r.fail(f"{key}.std", f"must be >= 0. Got {b!r} instead.")
        return Normal(a, b)
    if name == "loguniform" and not a > 0:
        r.fail(f"{key}.low", f"must be > 0 (log-uniform). Got {a!r} instead.")
    if not a < b:
        r.fail(f"{key}.high", f"must be > low ({a!r}). Got {b!r} instead.")
    return LogUniform(a, b) if name == "loguniform" else Uniform(a, b)


def _int(value: object, key: str, r: SweepReader) -> int:
    if isinstance(value, bool) or not isinstance(value, int):
        r.fail_type(key, f"must be an integer. Got {value!r} instead.")
    return int(value)


def _choice(table: Mapping[str, object], key: str, r: SweepReader) -> Choice:
    values = table["values"]
    if not isinstance(values, list | tuple) or not values:
        r.fail(f"{key}.values", f"must be a non-empty array of values. Got {values!r} instead.")
    items = tuple(r.value(v, f"{key}.values[{k}]") for k, v in enumerate(values))
    weights = table.get("weights")
    if weights is None:
        return Choice(items)
    if not isinstance(weights, list | tuple) or len(weights) != len(items):
        r.fail(
            f"{key}.weights",
            f"must be an array of {len(items)} numbers >= 0 (one per value). "
            f"Got {weights!r} instead.",
        )
    w = tuple(r.real(x, f"{key}.weights[{k}]") for k, x in enumerate(weights))
    if any(x < 0 for x in w) or not sum(w) > 0:
        r.fail(f"{key}.weights", f"must be >= 0 and not all 0. Got {list(weights)!r} instead.")
    return Choice(items, w)
