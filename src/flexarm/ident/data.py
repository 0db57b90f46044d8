"""Reading identification data: named or numbered columns of ``.csv``, text or ``.npz`` files.

Formats
-------
* ``.npz``: 1-D arrays named by their keys (all of one length), or a single
  2-D table whose columns are numbered;
* ``.csv``: comma-separated (Python's :mod:`csv`, strict quoting);
* anything else: whitespace-separated text, ``#`` starts a comment;
* any text file with ``delimiter`` given (``";"``, ``"\t"``, ...): separated by
  it (Python's :mod:`csv`).

A text file has a header when its first line has a non-numeric cell. Empty
cells and ``nan`` read as NaN; only the chosen columns must be numeric. Every
problem with a user's file — missing, unreadable, not text, ragged rows, an
unknown column, a non-numeric cell, no data — raises :class:`DataError` (a
:class:`~flexarm.errors.InvalidValueError`) with a one-line message naming the
file, the line and column where it applies, and the delimiter assumed.
"""

from __future__ import annotations

import csv
import math
import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from .._types import F64
from ..errors import InvalidValueError

__all__ = ["DataError", "load_columns", "read_xy"]


class DataError(InvalidValueError):
    """A data file that cannot give the requested columns (one-line message)."""


_OTHER_DELIMITERS = (";", "\t", "|", ",")


def _separator(path: Path, delimiter: str | None) -> str | None:
    """The delimiter in use: the one given, ``","`` for ``.csv``, None for whitespace."""
    if delimiter is not None:
        return delimiter
    return "," if path.suffix.lower() == ".csv" else None


def _layout(path: Path, delimiter: str | None) -> str:
    sep = _separator(path, delimiter)
    if sep is None:
        return "whitespace-separated text"
    return "comma-separated CSV" if sep == "," else f"text separated by {sep!r}"


def _hint(path: Path, delimiter: str | None, first_line: str) -> str:
    """How the file was read, and a guess at its delimiter when another one shows."""
    sep = _separator(path, delimiter)
    guess = next((d for d in _OTHER_DELIMITERS if d != sep and d in first_line), None)
    text = f"read as {_layout(path, delimiter)}"
    if guess is not None:
        text += (
            f"; its lines contain {guess!r}: give delimiter={guess!r} (--delimiter) if "
            "that separates the columns"
        )
    return text


def _rows(path: Path, delimiter: str | None = None) -> list[tuple[int, list[str]]]:
    """``(line number, cells)`` of the non-blank lines: separated by ``delimiter``, by
    commas for ``.csv``, else by whitespace."""
    try:
        with open(path, newline="", encoding="utf-8") as f:
            text = f.read()
    except UnicodeDecodeError:
        raise DataError(f"{str(path)!r} is not a UTF-8 text file (nor .npz)") from None
    except OSError as exc:
        raise DataError(f"{str(path)!r} cannot be read ({exc.strerror or exc})") from None
    lines = text.splitlines()
    sep = _separator(path, delimiter)
    if sep is not None:
        try:
            parsed = list(csv.reader(lines, delimiter=sep, strict=True))
        except csv.Error as exc:
            raise DataError(
                f"{str(path)!r} is not valid {_layout(path, delimiter)}: {exc}"
            ) from None
        return [(k + 1, [c.strip() for c in row]) for k, row in enumerate(parsed) if row]
    out = []
    for k, line in enumerate(lines):
        body = line.split("#", 1)[0].split()
        if body:
            out.append((k + 1, body))
    return out


def _is_number(cell: str) -> bool:
    try:
        float(cell)
    except ValueError:
        return False
    return True


def _pick(spec: str | int, names: list[str] | None, width: int, path: Path, how: str = "") -> int:
    """Column index of ``spec``: a header name, else a 0-based index (``how``: how the
    file was read, for the message)."""
    if isinstance(spec, str) and names is not None and spec in names:
        return names.index(spec)
    how = f"; {how}" if how else ""
    try:
        index = int(spec)
    except ValueError:
        known = f"columns: {', '.join(names)}" if names else "the file has no header"
        raise DataError(f"{str(path)!r}: no column named {spec!r} ({known}{how})") from None
    if not 0 <= index < width:
        raise DataError(
            f"{str(path)!r}: column index {index} is out of range ({width} column(s){how})"
        )
    return index


def _load_npz(path: Path, columns: Sequence[str | int]) -> tuple[F64, ...]:
    try:
        with np.load(path, allow_pickle=False) as z:
            arrays = {k: z[k] for k in z.files}
    except Exception as exc:  # zipfile/OSError/ValueError: all mean "not a readable .npz"
        raise DataError(f"{str(path)!r} is not a readable .npz file ({exc})") from None
    if not arrays:
        raise DataError(f"{str(path)!r} holds no arrays")
    if len(arrays) == 1 and next(iter(arrays.values())).ndim == 2:
        table = next(iter(arrays.values()))
        names: list[str] | None = None
        cols = [table[:, j] for j in range(table.shape[1])]
    else:
        names = list(arrays)
        cols = list(arrays.values())
        bad = [k for k, a in arrays.items() if a.ndim != 1]
        if bad:
            raise DataError(
                f"{str(path)!r}: array {bad[0]!r} is not one-dimensional (an .npz holds 1-D "
                "columns, or one 2-D table)"
            )
        lengths = {a.shape[0] for a in cols}
        if len(lengths) > 1:
            raise DataError(f"{str(path)!r}: the arrays have different lengths {sorted(lengths)}")
    out = []
    for spec in columns:
        j = _pick(spec, names, len(cols), path)
        col = cols[j]
        label = names[j] if names else str(j)
        if col.dtype.kind not in "biuf":
            raise DataError(f"{str(path)!r}: column {label!r} is not numeric (dtype {col.dtype})")
        out.append(np.asarray(col, dtype=np.float64))
    return tuple(out)


def load_columns(
    path: str | os.PathLike[str],
    columns: Sequence[str | int],
    *,
    delimiter: str | None = None,
) -> tuple[F64, ...]:
    """Read the named or numbered columns of a data file as float arrays (module docstring).

    Parameters
    ----------
    path : str or os.PathLike
        The data file.
    columns : sequence of str or int
        Each a header name or a 0-based column index (a string of digits that
        is not a header name counts as an index).
    delimiter : str, optional
        One character separating the columns of a text file (default: ``","``
        for ``.csv``, whitespace otherwise). Not for ``.npz``.

    Returns
    -------
    tuple of ndarray, each of shape (n,)
        The columns, in the order asked for (units as in the file); NaN for
        empty cells.

    Raises
    ------
    DataError
        Missing or unreadable file, ragged rows, an unknown column, a
        non-numeric cell or no data rows; the message is one line.

    Examples
    --------
    >>> import pathlib, tempfile
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "d.csv"
    >>> _ = p.write_text("t,u\\n0,1.5\\n1,\\n")
    >>> load_columns(p, ["u", 0])
    (array([1.5, nan]), array([0., 1.]))
    """
    p = Path(path)
    if not p.exists():
        raise DataError(f"{str(p)!r} does not exist")
    if not p.is_file():
        raise DataError(f"{str(p)!r} is not a file")
    if delimiter is not None and (not isinstance(delimiter, str) or len(delimiter) != 1):
        raise DataError(
            f"The 'delimiter' parameter of load_columns must be one character. Got "
            f"{delimiter!r} instead."
        )
    if p.suffix.lower() == ".npz":
        return _load_npz(p, columns)
    rows = _rows(p, delimiter)
    layout = _layout(p, delimiter)
    if not rows:
        raise DataError(f"{str(p)!r} holds no data")
    how = _hint(p, delimiter, _first_line(p))
    names: list[str] | None = None
    if not all(_is_number(c) or c == "" for c in rows[0][1]):
        names = rows[0][1]
        rows = rows[1:]
    width = len(names) if names is not None else len(rows[0][1]) if rows else 0
    if not rows:
        raise DataError(f"{str(p)!r} has a header but no data rows")
    picked = [_pick(spec, names, width, p, how) for spec in columns]
    out = [np.empty(len(rows)) for _ in picked]
    for r, (line, cells) in enumerate(rows):
        if len(cells) != width:
            raise DataError(
                f"{str(p)!r} line {line}: {len(cells)} field(s), expected {width} like the "
                f"{'header' if names is not None else 'first line'} ({how})"
            )
        for col, j in zip(out, picked, strict=True):
            cell = cells[j]
            if cell == "":
                col[r] = math.nan
                continue
            try:
                col[r] = float(cell)
            except ValueError:
                label = names[j] if names is not None else str(j)
                raise DataError(
                    f"{str(p)!r} line {line}, column {label!r}: {cell!r} is not a number "
                    f"(read as {layout})"
                ) from None
    return tuple(out)


def _first_line(path: Path) -> str:
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            return f.readline()
    except OSError:  # pragma: no cover - read a moment ago
        return ""


def read_xy(
    path: str | os.PathLike[str],
    x: str | int = 0,
    y: str | int = 1,
    *,
    drop_nan: bool = False,
    delimiter: str | None = None,
) -> tuple[F64, F64, int]:
    """Two columns of a data file for identification: finite, at least two rows.

    Parameters
    ----------
    path : str or os.PathLike
        The data file (:func:`load_columns`).
    x, y : str or int, default 0 and 1
        Input and output columns: header names or 0-based indices.
    drop_nan : bool, default False
        Drop the rows with NaN (or empty cells) in either column; otherwise such
        rows are an error.
    delimiter : str, optional
        As for :func:`load_columns`.

    Returns
    -------
    x, y : ndarray, shape (n,)
        The columns without the dropped rows (units as in the file).
    dropped : int
        Rows dropped.

    Raises
    ------
    DataError
        As :func:`load_columns`; NaN rows without ``drop_nan``; infinite
        values; fewer than two rows.
    """
    xs, ys = load_columns(path, [x, y], delimiter=delimiter)
    bad = np.isnan(xs) | np.isnan(ys)
    dropped = int(bad.sum())
    where = f"{str(Path(path))!r}"
    if dropped and not drop_nan:
        first = int(np.argmax(bad))
        raise DataError(
            f"{where}: {dropped} row(s) have NaN or empty cells in the chosen columns (the "
            f"first is data row {first + 1}); drop_nan=True (--drop-nan) drops them"
        )
    xs, ys = xs[~bad], ys[~bad]
    if not (np.all(np.isfinite(xs)) and np.all(np.isfinite(ys))):
        raise DataError(f"{where}: the chosen columns hold infinite values")
    if xs.shape[0] < 2:
        raise DataError(f"{where}: need at least 2 data rows, got {xs.shape[0]}")
    return xs, ys, dropped
