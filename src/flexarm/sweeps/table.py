"""The tidy table of a sweep: one row per run, one column per parameter or metric.

Columns, in order: ``run`` (the run's index in the sweep), ``run_id`` (the hash
of its scenario), each swept parameter under its dotted key
(``sensor.noise_std``), ``status`` (``ok``, ``diverged``, ``error``),
``message`` (why, for a run that is not ``ok``), ``sim_time_s`` (the simulated
time reached, s), the metrics of :meth:`flexarm.SimulationResult.metrics`
(``corner_errors_m`` as ``corner_errors_m[0]``, ``corner_errors_m[1]``, ...;
NaN where a run did not finish) and ``wall_time_s`` (the run's own time, s).

:class:`SweepTable` holds the columns as NumPy arrays, with no dependency on
pandas: :meth:`~SweepTable.to_pandas` gives a DataFrame, :meth:`~SweepTable.to_numpy`
a structured array. CSV is always written (:meth:`~SweepTable.write_csv`:
floats written with Python's shortest round-tripping ``repr``, NaN as an empty
field, booleans as ``true``/``false``), Parquet when pyarrow is installed
(``pip install 'flexarm[sweep]'``), which keeps the column types.

Examples
--------
>>> t = SweepTable.from_columns({"run": [0, 1], "run_id": ["a1", "b2"], "x.y": [0.5, 1.5],
...                             "status": ["ok", "error"], "message": ["", "bad"],
...                             "sim_time_s": [1.0, float("nan")], "rms_error_m": [0.1, None],
...                             "wall_time_s": [0.2, float("nan")]})
>>> t.parameters, t.metrics, len(t)
(('x.y',), ('rms_error_m',), 2)
>>> t.counts()
{'ok': 1, 'diverged': 0, 'error': 1}
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import NDArray

from .._io import JSONValue, atomic_path
from ..errors import InvalidValueError
from .reader import Value
from .records import STATUSES, Record
from .spec import SweepRun

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["PARQUET_EXTRA", "Cell", "SweepTable", "have_pyarrow"]

PARQUET_EXTRA = "pip install 'flexarm[sweep]'"
"""What installs pyarrow for Parquet files (the ``dask`` extra has it too)."""

Cell = str | int | float | bool
"""One value of the table."""

_FRONT = ("run", "run_id")
_MIDDLE = ("status", "message", "sim_time_s")
_BACK = ("wall_time_s",)
_INT = re.compile(r"[-+]?\d+")
_META = b"flexarm.sweep"


def have_pyarrow() -> bool:
    """Whether pyarrow (Parquet files) can be imported."""
    try:
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        return False
    return True


@dataclass(frozen=True, eq=False)
class SweepTable:
    """One row per run of a sweep: the swept parameters, the status and the metrics.

    Parameters
    ----------
    columns : dict of str to ndarray
        Every column (module docstring), all of one length, in order.
    parameters : tuple of str
        The parameter columns (dotted keys), in order.
    metrics : tuple of str
        The metric columns, in order.
    info : dict
        How the sweep ran (source, runs resumed from the journal, wall time in
        s, workers, scheduler, output files); not compared by :meth:`equals`.
    """

    columns: dict[str, NDArray[np.generic]]
    parameters: tuple[str, ...] = ()
    metrics: tuple[str, ...] = ()
    info: dict[str, JSONValue] = field(default_factory=dict)

    def __post_init__(self) -> None:
        lengths = {len(c) for c in self.columns.values()}
        if len(lengths) > 1:
            raise InvalidValueError(
                f"The 'columns' parameter of SweepTable must hold columns of one length. "
                f"Got lengths {sorted(lengths)} instead."
            )
        for name in (*_FRONT, *_MIDDLE, *_BACK, *self.parameters, *self.metrics):
            if name not in self.columns:
                raise InvalidValueError(
                    f"The 'columns' parameter of SweepTable must have a column '{name}'."
                )
        for column in self.columns.values():
            column.flags.writeable = False

    # ------------------------------------------------------------------ building
    @classmethod
    def from_records(
        cls,
        runs: Sequence[SweepRun],
        records: Mapping[str, Record],
        parameters: Sequence[str],
        metrics: Sequence[str],
        info: dict[str, JSONValue] | None = None,
    ) -> SweepTable:
        """The table of ``runs`` (in order) from their records (by run id).

        Parameters
        ----------
        runs : sequence of SweepRun
            One row each; runs with no record are left out (an interrupted sweep).
        records : mapping of str to Record
            The finished runs by run id (:mod:`flexarm.sweeps.records`).
        parameters : sequence of str
            The swept keys, in order.
        metrics : sequence of str
            The metrics to keep (names of :data:`~flexarm.sweeps.spec.METRICS`).
        info : dict, optional
            Stored as ``info``.
        """
        done = [(run, records[run.run_id]) for run in runs if run.run_id in records]
        cols: dict[str, list[object]] = {
            "run": [run.index for run, _ in done],
            "run_id": [run.run_id for run, _ in done],
        }
        for key in parameters:
            cols[key] = [run.params.get(key, _MISSING) for run, _ in done]
        cols["status"] = [rec["status"] for _, rec in done]
        cols["message"] = [rec["message"] for _, rec in done]
        cols["sim_time_s"] = [rec["sim_time_s"] for _, rec in done]
        for name in metrics:
            values: list[object] = [rec["metrics"].get(name, math.nan) for _, rec in done]
            if name == "corner_errors_m":
                width = max((len(v) for v in values if isinstance(v, list)), default=0)
                for k in range(width):
                    cols[f"{name}[{k}]"] = [
                        v[k] if isinstance(v, list) and k < len(v) else math.nan for v in values
                    ]
            else:
                cols[name] = values
        cols["wall_time_s"] = [rec["wall_time_s"] for _, rec in done]
        return cls.from_columns(cols, parameters=tuple(parameters), info=info)

    @classmethod
    def from_columns(
        cls,
        columns: Mapping[str, Sequence[object]],
        parameters: tuple[str, ...] | None = None,
        info: dict[str, JSONValue] | None = None,
    ) -> SweepTable:
        """A table from lists of Python values, in the column layout of the module docstring.

        Parameter columns (default: those between ``run_id`` and ``status``) get
        the narrowest type that holds them (bool, int, float, str; JSON text for
        arrays, tables and mixed types; a missing value makes ints floats (NaN)
        and is ``""`` in text); the others are typed by name.
        """
        names = list(columns)
        if parameters is None:
            parameters = tuple(names[names.index("run_id") + 1 : names.index("status")])
        metrics = tuple(names[names.index("sim_time_s") + 1 : names.index("wall_time_s")])
        typed: dict[str, NDArray[np.generic]] = {}
        for name, values in columns.items():
            if name == "run":
                typed[name] = np.array(values, dtype=np.int64)
            elif name in ("run_id", "status", "message"):
                typed[name] = np.array([str(v) for v in values], dtype=str)
            elif name in parameters:
                typed[name] = _parameter_column(list(values))
            else:
                typed[name] = np.array(
                    [math.nan if v is None else v for v in values], dtype=np.float64
                )
        return cls(typed, parameters=parameters, metrics=metrics, info=dict(info or {}))

    # ------------------------------------------------------------------ access
    def __len__(self) -> int:
        return len(self.columns["run"])

    def __getitem__(self, name: str) -> NDArray[np.generic]:
        return self.columns[name]

    def __contains__(self, name: object) -> bool:
        return name in self.columns

    def __repr__(self) -> str:
        c = self.counts()
        return (
            f"SweepTable({len(self)} runs: {c['ok']} ok, {c['diverged']} diverged, "
            f"{c['error']} error; parameters {list(self.parameters)})"
        )

    @property
    def column_names(self) -> tuple[str, ...]:
        """Every column, in order."""
        return tuple(self.columns)

    def rows(self) -> list[dict[str, Cell]]:
        """Each row as ``{column: Python value}``."""
        names = self.column_names
        lists = [self.columns[n].tolist() for n in names]
        return [dict(zip(names, values, strict=True)) for values in zip(*lists, strict=True)]

    def counts(self) -> dict[str, int]:
        """How many runs have each status: ``{"ok": ..., "diverged": ..., "error": ...}``."""
        status = self.columns["status"]
        return {s: int(np.count_nonzero(status == s)) for s in STATUSES}

    def best(self, metric: str = "rms_error_m", *, largest: bool = False) -> dict[str, Cell] | None:
        """The ``ok`` row with the smallest (``largest``: the largest) finite ``metric``.

        None when no ``ok`` run has a finite value. Ties go to the first run.
        """
        if metric not in self.columns:
            raise InvalidValueError(
                f"The 'metric' parameter of SweepTable.best must be one of {self.metrics}. "
                f"Got {metric!r} instead."
            )
        values = np.asarray(self.columns[metric], dtype=np.float64)
        ok = (self.columns["status"] == "ok") & np.isfinite(values)
        if not ok.any():
            return None
        candidates = np.flatnonzero(ok)
        pick = values[candidates].argmax() if largest else values[candidates].argmin()
        return self.rows()[int(candidates[pick])]

    def equals(self, other: SweepTable, ignore: Sequence[str] = ()) -> bool:
        """Same columns, same order, same values bit for bit (NaN equal to NaN),
        except the columns ``ignore`` (e.g. ``("wall_time_s",)``)."""
        if self.column_names != other.column_names or len(self) != len(other):
            return False
        for name in self.column_names:
            if name in ignore:
                continue
            a, b = self.columns[name], other.columns[name]
            if a.dtype.kind != b.dtype.kind:
                return False
            same = a.tobytes() == b.tobytes() if a.dtype.kind == "f" else np.array_equal(a, b)
            if not same:
                return False
        return True

    # ------------------------------------------------------------------ export
    def to_pandas(self) -> pd.DataFrame:
        """A pandas DataFrame with the same columns (needs pandas)."""
        import pandas as pd

        return pd.DataFrame({name: column for name, column in self.columns.items()})

    def to_numpy(self) -> NDArray[np.void]:
        """A NumPy structured array, one field per column."""
        dtype = [(name, column.dtype) for name, column in self.columns.items()]
        out = np.empty(len(self), dtype=dtype)
        for name, column in self.columns.items():
            out[name] = column
        return out

    def write_csv(self, path: str | os.PathLike[str]) -> None:
        """Write the table as CSV (atomically; module docstring for the format)."""
        with atomic_path(path) as tmp, open(tmp, "w", newline="", encoding="utf-8") as fh:
            writer = csv.writer(fh, lineterminator="\n")
            writer.writerow(self.column_names)
            for row in self.rows():
                writer.writerow([_cell_text(v) for v in row.values()])

    @classmethod
    def read_csv(cls, path: str | os.PathLike[str]) -> SweepTable:
        """Read a table written by :meth:`write_csv`.

        CSV has no types: a parameter column is read as bool, int, float or text,
        whichever holds every value (Parquet keeps the types exactly).
        """
        with open(path, newline="", encoding="utf-8") as fh:
            reader = csv.reader(fh)
            try:
                header = next(reader)
            except StopIteration:
                raise InvalidValueError(
                    f"{os.fspath(path)}: an empty file, not a sweep table"
                ) from None
            body = list(reader)
        for name in (*_FRONT, *_MIDDLE, *_BACK):
            if name not in header:
                raise InvalidValueError(f"{os.fspath(path)}: not a sweep table (no '{name}')")
        texts = {name: [row[k] for row in body] for k, name in enumerate(header)}
        params = tuple(header[header.index("run_id") + 1 : header.index("status")])
        cols: dict[str, list[object]] = {}
        for name, values in texts.items():
            if name in params:
                cols[name] = _parse_parameter(values)
            elif name in ("run_id", "status", "message"):
                cols[name] = list(values)
            elif name == "run":
                cols[name] = [int(v) for v in values]
            else:
                cols[name] = [math.nan if v == "" else float(v) for v in values]
        return cls.from_columns(cols, parameters=params)

    def write_parquet(self, path: str | os.PathLike[str]) -> None:
        """Write the table as Parquet, types kept (atomically; needs pyarrow).

        Raises
        ------
        InvalidValueError
            If pyarrow is not installed (the message says how to install it).
        """
        pa, pq = _pyarrow()
        table = pa.table({name: pa.array(column) for name, column in self.columns.items()})
        meta = {"parameters": list(self.parameters), "metrics": list(self.metrics)}
        table = table.replace_schema_metadata({_META: json.dumps(meta).encode()})
        with atomic_path(path) as tmp:
            pq.write_table(table, tmp)

    @classmethod
    def read_parquet(cls, path: str | os.PathLike[str]) -> SweepTable:
        """Read a table written by :meth:`write_parquet` (needs pyarrow)."""
        _, pq = _pyarrow()
        table = pq.read_table(path)
        meta = json.loads((table.schema.metadata or {}).get(_META, b"{}"))
        columns: dict[str, NDArray[np.generic]] = {}
        for name in table.column_names:
            values = table.column(name).to_numpy(zero_copy_only=False)
            columns[name] = values.astype(str) if values.dtype == object else values
        return cls(
            columns,
            parameters=tuple(meta.get("parameters", ())),
            metrics=tuple(meta.get("metrics", ())),
        )


# ------------------------------------------------------------------ columns
class _Missing:
    """A parameter a run does not set (a key of another grid)."""

    def __repr__(self) -> str:
        return "MISSING"


_MISSING = _Missing()


def _parameter_column(values: list[object]) -> NDArray[np.generic]:
    present = [v for v in values if v is not _MISSING]
    complete = len(present) == len(values)
    if complete and present and all(isinstance(v, bool) for v in present):
        return np.array(present, dtype=bool)
    ints = [v for v in present if isinstance(v, int) and not isinstance(v, bool)]
    if complete and len(ints) == len(present) and all(-(2**63) <= v < 2**63 for v in ints):
        return np.array(ints, dtype=np.int64)
    if all(isinstance(v, int | float) and not isinstance(v, bool) for v in present):
        return np.array([math.nan if v is _MISSING else v for v in values], dtype=np.float64)
    if all(isinstance(v, str) for v in present):
        return np.array(["" if v is _MISSING else v for v in values], dtype=str)
    return np.array(
        ["" if v is _MISSING else json.dumps(v, sort_keys=True) for v in values], dtype=str
    )


def _parse_parameter(texts: list[str]) -> list[object]:
    if texts and all(t in ("true", "false") for t in texts):
        return [t == "true" for t in texts]
    if texts and all(_INT.fullmatch(t) for t in texts):
        return [int(t) for t in texts]
    try:
        return [math.nan if t == "" else float(t) for t in texts]
    except ValueError:
        return list(texts)


def _cell_text(value: Cell | Value) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, float):
        return "" if math.isnan(value) else repr(value)
    return str(value)


def _pyarrow() -> tuple[ModuleType, ModuleType]:
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        raise InvalidValueError(
            f"Parquet files need pyarrow, which is not installed: {PARQUET_EXTRA}"
        ) from None
    return pa, pq
