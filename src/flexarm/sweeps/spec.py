"""A sweep: a base scenario, the parameters that vary, and the runs they make.

A sweep file is TOML::

    base = "paper_square.toml"     # a scenario file (relative to this file), or
    # [base]                       # the scenario inline (file = "..." to start from one)
    # simulation.duration = 2.0

    [grid]                         # every combination (the last key varies fastest)
    "sensor.noise_std" = [0.0, 1e-4, 1e-3]
    "controller.zeta" = [0.5, 0.707]

    [monte_carlo]                  # n draws, reproducible from the seed
    n = 100
    seed = 42
    "simulation.seed" = { distribution = "integers", low = 0, high = 1000000 }
    "arm.payload_mass" = { distribution = "uniform", low = 0.0, high = 1.0 }

    [sweep]
    metrics = ["rms_error_m", "max_error_m"]   # the table's metric columns (default: all)

A key is a dotted key into the scenario schema (:mod:`flexarm.sim.scenario`;
:mod:`flexarm.sweeps.keys`): ``"sensor.noise_std"``, ``"controller.kp"``,
``"arm.links[1].length"``; ``sensor.noise_std = [...]`` without quotes is the
same key. ``[grid]`` is scikit-learn's ``ParameterGrid``: a table of lists, or an
array of tables (``[[grid]]``) for several grids one after the other (a key that
only some kinds take goes in a grid of its own). ``[monte_carlo]`` is
``ParameterSampler`` with explicit distributions (:mod:`flexarm.sweeps.distributions`).
With both, every grid point is run with each of the ``n`` draws, the same draws
at every point (common random numbers).

Examples
--------
>>> spec = SweepSpec.from_dict({
...     "base": {"simulation": {"duration": 0.05}},
...     "grid": {"controller.zeta": [0.5, 0.7], "sensor": {"noise_std": [0.0, 1e-4]}},
... })
>>> spec.n_runs, spec.parameters
(4, ('controller.zeta', 'sensor.noise_std'))
>>> [run.params["sensor.noise_std"] for run in spec.runs]
[0.0, 0.0001, 0.0, 0.0001]
"""

from __future__ import annotations

import itertools
import math
import os
from collections.abc import Iterator, Mapping
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path

from .._config import read_toml
from ..errors import ScenarioError, SweepError
from ..sim.scenario_schema import SECTIONS, apply_overrides, read_scenario
from .distributions import Distribution, distribution_from_table, key_rng
from .keys import KeyPathError, flatten, parse_key, run_id, with_changes
from .reader import SweepReader, Value

__all__ = [
    "MAX_RUNS",
    "METRICS",
    "Grid",
    "MonteCarlo",
    "SweepRun",
    "SweepSpec",
    "load_sweep",
    "read_sweep",
]

METRICS = (
    "rms_error_m",
    "max_error_m",
    "corner_errors_m",
    "residual_vibration_m",
    "settling_time_s",
    "control_effort_N2m2s",
    "max_torque_Nm",
)
"""The metrics of :meth:`flexarm.SimulationResult.metrics` a sweep's table can hold
(``sim_time_s`` and ``wall_time_s`` are always there)."""

MAX_RUNS = 1_000_000
"""The most runs one sweep may expand to (split a larger study into sweeps)."""

_FILE_SECTIONS = ("base", "grid", "monte_carlo", "sweep")


@dataclass(frozen=True)
class Grid:
    """Every combination of the values of some keys (scikit-learn's ``ParameterGrid``).

    Parameters
    ----------
    axes : tuple of (str, tuple of value)
        Dotted keys and their values, in order; the last key varies fastest.
    """

    axes: tuple[tuple[str, tuple[Value, ...]], ...]

    def __len__(self) -> int:
        return math.prod(len(values) for _, values in self.axes)

    @property
    def keys(self) -> tuple[str, ...]:
        """The swept keys, in order."""
        return tuple(key for key, _ in self.axes)

    def points(self) -> Iterator[dict[str, Value]]:
        """Each combination, as ``{key: value}``."""
        keys = self.keys
        for values in itertools.product(*(v for _, v in self.axes)):
            yield dict(zip(keys, values, strict=True))


@dataclass(frozen=True)
class MonteCarlo:
    """``n`` random draws of some keys (scikit-learn's ``ParameterSampler``).

    Parameters
    ----------
    n : int
        Draws (>= 1).
    seed : int
        Seed of every draw (>= 0); key ``k``'s draws come from
        :func:`~flexarm.sweeps.distributions.key_rng` ``(seed, k)``.
    draws : tuple of (str, Distribution)
        Dotted keys and their distributions, in order.
    """

    n: int
    seed: int
    draws: tuple[tuple[str, Distribution], ...]

    @property
    def keys(self) -> tuple[str, ...]:
        """The drawn keys, in order."""
        return tuple(key for key, _ in self.draws)

    def samples(self) -> list[dict[str, Value]]:
        """The ``n`` draws, each as ``{key: value}``."""
        columns = {key: dist.draw(key_rng(self.seed, key), self.n) for key, dist in self.draws}
        return [{key: columns[key][i] for key in columns} for i in range(self.n)]


@dataclass(frozen=True)
class SweepRun:
    """One run of a sweep.

    Parameters
    ----------
    index : int
        Position in the sweep's expansion (0-based): the table's ``run`` column.
    run_id : str
        :func:`~flexarm.sweeps.keys.run_id` of the run's full scenario mapping.
    params : dict
        The swept keys' values in this run.
    """

    index: int
    run_id: str
    params: dict[str, Value] = field(compare=False)


@dataclass(frozen=True)
class SweepSpec:
    """A sweep: the base scenario, its grids and Monte Carlo draws, the metrics kept.

    Parameters
    ----------
    base : dict
        The base scenario mapping (the schema of :mod:`flexarm.sim.scenario`).
    grids : tuple of Grid
        Run one after the other (a ``[[grid]]`` array of tables).
    monte_carlo : MonteCarlo, optional
        Draws combined with every grid point (alone if there is no grid).
    metrics : tuple of str
        The metric columns of the table (a subset of :data:`METRICS`, in order).
    source : str
        Where it came from (the file name), named in every message.

    Raises
    ------
    SweepError
        Nothing to sweep, a key both in a grid and drawn, a key inside another
        swept key, an unknown metric, more than :data:`MAX_RUNS` runs.
    """

    base: dict[str, Value] = field(default_factory=dict)
    grids: tuple[Grid, ...] = ()
    monte_carlo: MonteCarlo | None = None
    metrics: tuple[str, ...] = METRICS
    source: str = "sweep"

    def __post_init__(self) -> None:
        r = SweepReader(self.source)
        if not self.grids and self.monte_carlo is None:
            r.fail(None, "nothing to sweep: give a [grid] or a [monte_carlo] section")
        for g, grid in enumerate(self.grids):
            if not grid.axes:
                r.fail(self._grid_name(g), "is empty: give at least one key = [values]")
        if self.monte_carlo is not None:
            mc = self.monte_carlo
            if not mc.draws:
                r.fail("monte_carlo", "draws no key: give key = { distribution = ... }")
            for key in set(mc.keys) & {k for grid in self.grids for k in grid.keys}:
                r.fail(f"monte_carlo.{key}", f"'{key}' is also in a grid: sweep it one way")
        for name in self.metrics:
            if name not in METRICS:
                r.fail("sweep.metrics", f"unknown metric '{name}' (metrics: {', '.join(METRICS)})")
        if self.n_runs > MAX_RUNS:
            r.fail(
                None,
                f"expands to {self.n_runs} runs, more than {MAX_RUNS}: split it into sweeps",
            )

    def _grid_name(self, g: int) -> str:
        return "grid" if len(self.grids) == 1 else f"grid[{g}]"

    # ------------------------------------------------------------------ expansion
    @property
    def n_runs(self) -> int:
        """How many runs the sweep expands to."""
        n = 1 if self.monte_carlo is None else self.monte_carlo.n
        return n * (sum(len(g) for g in self.grids) if self.grids else 1)

    @property
    def parameters(self) -> tuple[str, ...]:
        """Every swept key, grids' first (in order), then the drawn ones."""
        keys = [k for grid in self.grids for k in grid.keys]
        if self.monte_carlo is not None:
            keys += self.monte_carlo.keys
        return tuple(dict.fromkeys(keys))

    def axis(self, key: str) -> str:
        """Where ``key`` is swept, for messages: ``"grid"``, ``"grid[1]"`` or ``"monte_carlo"``."""
        for g, grid in enumerate(self.grids):
            if key in grid.keys:
                return self._grid_name(g)
        return "monte_carlo"

    @cached_property
    def runs(self) -> tuple[SweepRun, ...]:
        """Every run, in order: grid points (each grid in turn) times Monte Carlo draws.

        Raises
        ------
        SweepError
            If a key cannot be set in the base scenario (an index beyond an
            array, a key inside something that is not a table).
        """
        draws: list[dict[str, Value]] = (
            [{}] if self.monte_carlo is None else self.monte_carlo.samples()
        )
        points = [p for grid in self.grids for p in grid.points()] if self.grids else [{}]
        runs = []
        for index, (point, draw) in enumerate(itertools.product(points, draws)):
            params = {**point, **draw}
            runs.append(SweepRun(index, run_id(self.scenario(params)), params))
        return tuple(runs)

    @property
    def first_runs(self) -> tuple[int, ...]:
        """The index of the first run of each grid (of the draws, without a grid)."""
        n = 1 if self.monte_carlo is None else self.monte_carlo.n
        sizes = [len(g) * n for g in self.grids] if self.grids else [n]
        return tuple(itertools.accumulate([0, *sizes[:-1]]))

    def scenario(self, params: Mapping[str, Value]) -> dict[str, Value]:
        """The full scenario mapping of a run with the swept values ``params``.

        Raises
        ------
        SweepError
            If a key cannot be set in the base scenario.
        """
        try:
            return with_changes(self.base, params)
        except KeyPathError as exc:
            raise SweepError(self.source, f"{self.axis(exc.key)}.{exc.key}", exc.reason) from None

    # ------------------------------------------------------------------ reading
    @classmethod
    def from_dict(
        cls,
        data: Mapping[str, object],
        source: str = "sweep",
        root: str | os.PathLike[str] | None = None,
    ) -> SweepSpec:
        """Build a sweep from a mapping with the schema of the module docstring.

        Parameters
        ----------
        data : mapping
            Sections to tables (as :func:`tomllib.load` returns them).
        source : str
            Named at the start of every message (the file name).
        root : path, optional
            Directory of a relative ``base`` file (default: the current directory).

        Raises
        ------
        SweepError, SweepTypeError
            For an unknown section or key, a missing key or a rejected value.
        """
        r = SweepReader(source)
        data = r.sections(data, _FILE_SECTIONS)
        options = r.as_table(data.get("sweep", {}), "sweep")
        r.keys(options, "sweep", ("metrics",))
        metrics = _metrics(r, options.get("metrics", list(METRICS)))
        base = _base(r, data.get("base", {}), Path(root) if root is not None else Path.cwd())
        grids = _grids(r, data["grid"]) if "grid" in data else ()
        mc = _monte_carlo(r, data["monte_carlo"]) if "monte_carlo" in data else None
        _check_nesting(r, [*(k for g in grids for k in g.keys), *(mc.keys if mc else ())], grids)
        return cls(base=base, grids=grids, monte_carlo=mc, metrics=metrics, source=source)


def read_sweep(path: str | os.PathLike[str]) -> dict[str, object]:
    """The raw mapping of a TOML sweep file (not yet checked: :meth:`SweepSpec.from_dict`).

    Raises
    ------
    SweepError
        If the file cannot be read or is not valid TOML.
    """
    return read_toml(path, SweepError, "sweep file")


def load_sweep(path: str | os.PathLike[str]) -> SweepSpec:
    """Read and check a sweep file; a relative ``base`` file is found beside it."""
    source = os.fspath(path)
    return SweepSpec.from_dict(read_sweep(path), source=source, root=Path(source).parent)


# ------------------------------------------------------------------ sections
def _metrics(r: SweepReader, value: object) -> tuple[str, ...]:
    if not isinstance(value, list | tuple) or not all(isinstance(v, str) for v in value):
        r.fail_type("sweep.metrics", f"must be an array of metric names. Got {value!r} instead.")
    if not value:
        r.fail("sweep.metrics", "must name at least one metric")
    if len(set(value)) != len(value):
        r.fail("sweep.metrics", f"names a metric twice. Got {list(value)!r}.")
    return tuple(value)


def _base(r: SweepReader, value: object, root: Path) -> dict[str, Value]:
    if isinstance(value, str):
        data: Mapping[str, object] = _read_base(r, value, root, "base")
    elif isinstance(value, Mapping):
        rest = {k: v for k, v in value.items() if k != "file"}
        data = rest
        if "file" in value:
            name = r.string(value["file"], "base.file")
            data = apply_overrides(_read_base(r, name, root, "base.file"), rest)
    else:
        r.fail_type(
            "base",
            f"must be a scenario file name or a table ([base]). Got {value!r} instead.",
        )
    for name, section in data.items():
        if name not in SECTIONS:
            what = "section" if isinstance(section, Mapping) else "key"
            r.fail("base", f"unknown {what} '{name}' (sections: {', '.join(SECTIONS)})")
    checked = r.value(data, "base")
    assert isinstance(checked, dict)
    return checked


def _read_base(r: SweepReader, name: str, root: Path, key: str) -> dict[str, object]:
    path = root / name
    try:
        return read_scenario(path)
    except ScenarioError as exc:
        r.fail(key, f"{name}: {exc.reason}")


def _grids(r: SweepReader, value: object) -> tuple[Grid, ...]:
    if isinstance(value, Mapping):
        return (_grid(r, value, "grid"),)
    if isinstance(value, list) and value and all(isinstance(g, Mapping) for g in value):
        return tuple(_grid(r, g, f"grid[{k}]") for k, g in enumerate(value))
    r.fail_type(
        "grid", f"must be a table ([grid]) or an array of tables ([[grid]]). Got {value!r} instead."
    )


def _grid(r: SweepReader, table: Mapping[str, object], name: str) -> Grid:
    axes = []
    for key, values in flatten(table):
        _key(r, key, name)
        if not isinstance(values, list | tuple):
            r.fail_type(
                f"{name}.{key}", f"must be an array of values to try. Got {values!r} instead."
            )
        if not values:
            r.fail(f"{name}.{key}", "is empty: give at least one value")
        checked = tuple(r.value(v, f"{name}.{key}[{k}]") for k, v in enumerate(values))
        axes.append((key, checked))
    if not axes:
        r.fail(name, "is empty: give at least one key = [values]")
    _no_repeats(r, [k for k, _ in axes], name)
    return Grid(tuple(axes))


def _monte_carlo(r: SweepReader, value: object) -> MonteCarlo:
    table = r.as_table(value, "monte_carlo")
    for required in ("n", "seed"):
        if required not in table:
            why = "the number of draws" if required == "n" else "the draws are reproducible from it"
            r.fail("monte_carlo", f"missing key 'monte_carlo.{required}' ({why})")
    n = r.integer(table["n"], "monte_carlo.n", 1)
    seed = r.integer(table["seed"], "monte_carlo.seed", 0)
    entries = {k: v for k, v in table.items() if k not in ("n", "seed")}
    draws = []
    for key, spec in flatten(entries, is_leaf=lambda t: "distribution" in t):
        _key(r, key, "monte_carlo")
        where = f"monte_carlo.{key}"
        if not isinstance(spec, Mapping):
            r.fail_type(
                where,
                "must be a table { distribution = 'uniform' | 'loguniform' | 'normal' | "
                f"'integers' | 'choice', ... }}. Got {spec!r} instead.",
            )
        draws.append((key, distribution_from_table(spec, where, r)))
    _no_repeats(r, [k for k, _ in draws], "monte_carlo")
    return MonteCarlo(n, seed, tuple(draws))


def _key(r: SweepReader, key: str, name: str) -> None:
    try:
        parse_key(key)
    except KeyPathError as exc:
        r.fail(f"{name}.{key}", exc.reason)


def _no_repeats(r: SweepReader, keys: list[str], name: str) -> None:
    seen = set()
    for key in keys:
        if key in seen:
            r.fail(f"{name}.{key}", "is given twice (quoted and as a table?)")
        seen.add(key)


def _check_nesting(r: SweepReader, keys: list[str], grids: tuple[Grid, ...]) -> None:
    """Refuse a key inside another swept key ('arm.joints' and 'arm.joints.stiffness')."""
    for a in keys:
        for b in keys:
            if b.startswith(a + ".") or b.startswith(a + "["):
                where = next((f"grid.{b}" for g in grids if b in g.keys), f"monte_carlo.{b}")
                r.fail(where, f"is inside '{a}', which is swept too: sweep one or the other")
