"""Measured records: which columns of which files are the inputs and the outputs.

A record is one measured run: a time column, the input of each driven joint
(a prescribed angle, a torque or a motor current) and the measured output
channels, each a column of a file with its unit. Columns may come from several
files (a logger that writes one file per signal). Files are read once:

* ``.mat`` (MATLAB, through :func:`scipy.io.loadmat`): a column is a variable,
  and for a matrix variable a column index (0-based);
* ``.npz``: a variable, and a column index for a matrix;
* ``.csv``, ``.txt``, ``.dat`` and other text: a column index (0-based), or a
  header name for a ``.csv`` file with a header row.

Values are converted to SI (:mod:`flexarm.calibration.units`); a record may be cut
to a time window ``[start, stop)`` (s, on the record's own clock), e.g. to fit
on the first 10 s of a run and validate on the rest. The time column must be
increasing and evenly spaced (the simulator steps through it).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .._types import F64
from ..errors import CalibrationError
from .units import UNITS, to_si, unit_quantity

__all__ = [
    "INPUT_KINDS",
    "MIN_SAMPLES",
    "ROLES",
    "Column",
    "InputColumn",
    "Record",
    "RecordSpec",
    "load_record",
]


INPUT_KINDS = {"angle": "angle", "torque": "torque", "current": "current"}
"""How a joint is driven -> the quantity its column measures: a prescribed angle
(the motor angle behind a flexible joint), a joint torque, or a motor current."""
ROLES = ("training", "validation")
"""What a record is for: fitting the parameters, or judging the fitted model."""
MIN_SAMPLES = 20
"""The fewest samples a record (after its window) may have."""


@dataclass(frozen=True)
class Column:
    """Where one signal is: a variable (or column) of a file, in a unit.

    Parameters
    ----------
    variable : str or int
        The variable of a ``.mat``/``.npz`` file, or the column (index or header
        name) of a text file.
    unit : str
        The unit of the values (:data:`flexarm.calibration.units.UNITS`).
    column : int, optional
        For a matrix variable, the column (0-based).
    file : str, optional
        The file (default: the record's).
    """

    variable: str | int
    unit: str
    column: int | None = None
    file: str | None = None


@dataclass(frozen=True)
class InputColumn:
    """How a joint is driven in a record: ``kind`` (a key of :data:`INPUT_KINDS`) and
    the column of its values."""

    joint: int
    kind: str
    values: Column


@dataclass(frozen=True)
class RecordSpec:
    """A record as a configuration file describes it (not yet read).

    Parameters
    ----------
    name : str
        Named in reports (default: the file, and the window).
    role : {"training", "validation"}
    time : Column
        The time column (s or ms).
    inputs : tuple of InputColumn
        One per driven joint (a joint without an input gets zero torque).
    outputs : dict of str to Column
        Measured channels, by the name of the output that predicts them.
    file : str, optional
        The default file of the columns.
    start, stop : float, optional
        The window of the record to keep, s on its own clock.
    """

    name: str
    role: str
    time: Column
    inputs: tuple[InputColumn, ...]
    outputs: dict[str, Column]
    file: str | None = None
    start: float | None = None
    stop: float | None = None


@dataclass(frozen=True)
class Record:
    """A record read: SI values on an evenly spaced time grid.

    Attributes
    ----------
    name, role : str
    files : tuple of str
        The files it was read from.
    t : ndarray, shape (K,)
        Times, s (the window's, on the record's clock).
    inputs : dict of int to (str, ndarray (K,))
        Joint -> (kind, values in rad, N m or A).
    outputs : dict of str to ndarray (K,)
        Measured channels in SI.
    """

    name: str
    role: str
    files: tuple[str, ...]
    t: F64
    inputs: dict[int, tuple[str, F64]]
    outputs: dict[str, F64]
    units: dict[str, str] = field(default_factory=dict)

    @property
    def dt(self) -> float:
        """The sample period, s."""
        return float(self.t[1] - self.t[0])

    @property
    def drive(self) -> str:
        """How the record drives the arm: ``"angle"`` if any joint's angle is
        prescribed, else ``"torque"`` (torques or currents, converted by the drives)."""
        return "angle" if any(k == "angle" for k, _ in self.inputs.values()) else "torque"


def _read_file(path: Path, source: str, key: str) -> Mapping[str, object] | F64:
    """A file's variables (``.mat``, ``.npz``) or its text as a 2-D array (with the
    header names as ``__header__`` when a ``.csv`` has one)."""
    if not path.is_file():
        raise CalibrationError(source, key, f"no such file: {path}")
    suffix = path.suffix.lower()
    try:
        if suffix == ".mat":
            from scipy.io import loadmat

            return dict(loadmat(path))
        if suffix == ".npz":
            with np.load(path, allow_pickle=False) as data:
                return {k: np.array(data[k]) for k in data.files}
        text = path.read_text()
    except (OSError, ValueError) as exc:
        raise CalibrationError(source, key, f"cannot read {path}: {exc}") from None
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.lstrip().startswith("#")]
    delimiter = "," if suffix == ".csv" else None
    header: list[str] | None = None
    if lines and suffix == ".csv":
        first = [c.strip() for c in lines[0].split(",")]
        try:
            [float(c) for c in first]
        except ValueError:
            header, lines = first, lines[1:]
    try:
        table = np.loadtxt(lines, delimiter=delimiter, ndmin=2)
    except ValueError as exc:
        raise CalibrationError(source, key, f"cannot read {path} as numbers: {exc}") from None
    if header is not None:
        return {"__table__": table, "__header__": np.array(header)}
    return np.asarray(table, dtype=np.float64)


def _values(
    col: Column,
    files: dict[Path, Mapping[str, object] | F64],
    root: Path,
    default: str | None,
    source: str,
    key: str,
) -> tuple[F64, str]:
    """The values of ``col`` (in its unit) and the file they came from."""
    name = col.file or default
    if name is None:
        raise CalibrationError(source, key, "names no file (give 'file' here or in the record)")
    path = Path(name) if os.path.isabs(name) else root / name
    if path not in files:
        files[path] = _read_file(path, source, key)
    data = files[path]
    if isinstance(data, np.ndarray) or "__table__" in data:
        table = data if isinstance(data, np.ndarray) else np.asarray(data["__table__"])
        index = col.variable
        if isinstance(index, str):
            header = [] if isinstance(data, np.ndarray) else list(np.asarray(data["__header__"]))
            if index not in header:
                raise CalibrationError(
                    source,
                    key,
                    f"{path.name} has no column {index!r} (columns: {header or 'none named'})",
                )
            index = header.index(index)
        if not 0 <= index < table.shape[1]:
            raise CalibrationError(
                source, key, f"{path.name} has {table.shape[1]} columns: no column {index}"
            )
        return np.asarray(table[:, index], dtype=np.float64), str(path)
    variable = str(col.variable)
    if variable not in data:
        known = sorted(k for k in data if not k.startswith("__"))
        raise CalibrationError(
            source, key, f"{path.name} has no variable {variable!r} (variables: {', '.join(known)})"
        )
    try:
        arr = np.asarray(data[variable], dtype=np.float64)
    except (TypeError, ValueError):
        raise CalibrationError(source, key, f"{path.name}: {variable!r} is not numeric") from None
    if arr.ndim == 2 and col.column is not None:
        if not 0 <= col.column < arr.shape[1]:
            raise CalibrationError(
                source,
                key,
                f"{path.name}: {variable!r} has {arr.shape[1]} columns: no column {col.column}",
            )
        arr = arr[:, col.column]
    elif arr.ndim == 2 and 1 in arr.shape:
        arr = arr.ravel()
    if arr.ndim != 1:
        raise CalibrationError(
            source,
            key,
            f"{path.name}: {variable!r} has shape {arr.shape}: give the column to take",
        )
    return np.ascontiguousarray(arr), str(path)


def load_record(spec: RecordSpec, root: str | os.PathLike[str], source: str, index: int) -> Record:
    """Read the columns of ``spec`` from files under ``root`` (for relative names).

    Raises
    ------
    CalibrationError
        Naming the record's key (``records[1].outputs.th12``) for a file or column
        that is missing, a unit unknown or of the wrong quantity, columns of unequal
        length, a time column that is not increasing and evenly spaced, or a record
        (window) shorter than :data:`MIN_SAMPLES` samples.
    """
    base = f"records[{index}]"
    root = Path(root)
    files: dict[Path, Mapping[str, object] | F64] = {}
    read: set[str] = set()

    def get(col: Column, key: str, quantity: str) -> F64:
        got = unit_quantity(col.unit)
        if got is None:
            raise CalibrationError(
                source, f"{key}.unit", f"unknown unit {col.unit!r} (units: {', '.join(UNITS)})"
            )
        if got != quantity:
            raise CalibrationError(
                source,
                f"{key}.unit",
                f"must be a unit of {quantity}. Got {col.unit!r} ({got}) instead.",
            )
        values, path = _values(col, files, root, spec.file, source, key)
        read.add(path)
        return to_si(values, col.unit)

    t = get(spec.time, f"{base}.time", "time")
    inputs = {
        ic.joint: (ic.kind, get(ic.values, f"{base}.inputs[{k}]", INPUT_KINDS[ic.kind]))
        for k, ic in enumerate(spec.inputs)
    }
    outputs: dict[str, F64] = {}
    for name, col in spec.outputs.items():
        quantity = unit_quantity(col.unit) or "?"
        outputs[name] = get(col, f"{base}.outputs.{name}", quantity)
    for name, values in (
        [("time", t)]
        + [(f"inputs[{k}]", v) for k, (_, v) in enumerate(inputs.values())]
        + [(f"outputs.{n}", v) for n, v in outputs.items()]
    ):
        if values.shape != t.shape:
            raise CalibrationError(
                source,
                f"{base}.{name}",
                f"has {values.shape[0]} samples where the time column has {t.shape[0]}",
            )
        if not np.all(np.isfinite(values)):
            raise CalibrationError(source, f"{base}.{name}", "holds values that are not finite")
    keep = np.ones(t.shape[0], dtype=bool)
    if spec.start is not None:
        keep &= t >= spec.start - 1e-9
    if spec.stop is not None:
        keep &= t < spec.stop - 1e-9
    kept = int(np.count_nonzero(keep))
    if kept < MIN_SAMPLES:
        raise CalibrationError(
            source, base, f"is too short: {kept} samples in its window (at least {MIN_SAMPLES})"
        )
    t = t[keep]
    steps = np.diff(t)
    dt = (t[-1] - t[0]) / (t.shape[0] - 1)
    if not dt > 0 or np.any(np.abs(steps - dt) > 1e-6 * dt + 1e-9):
        raise CalibrationError(
            source,
            f"{base}.time",
            f"must be increasing and evenly spaced. Got steps from {steps.min():.6g} to "
            f"{steps.max():.6g} s instead.",
        )
    return Record(
        name=spec.name,
        role=spec.role,
        files=tuple(sorted(read)),
        t=np.ascontiguousarray(t),
        inputs={j: (kind, np.ascontiguousarray(v[keep])) for j, (kind, v) in inputs.items()},
        outputs={n: np.ascontiguousarray(v[keep]) for n, v in outputs.items()},
        units={n: c.unit for n, c in spec.outputs.items()},
    )
