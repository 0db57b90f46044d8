"""The files of the identification results: a directory, CSV tables, a figure of one plot.

Every result of :mod:`flexarm.ident` (and of the robot-joint study) writes into a
directory it creates if needed, each file atomically (a temporary file beside it is
renamed into place once complete, :func:`flexarm._io.atomic_path`), its figures in
the style of :mod:`flexarm.figures` and the format asked for.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_path
from ..figures import SINGLE_COLUMN, FigureFormat, new_figure, save_figure, style

if TYPE_CHECKING:  # pragma: no cover
    from matplotlib.axes import Axes

__all__ = [
    "output_directory",
    "save_axes_figure",
    "save_docstring",
    "save_table_and_plot",
    "write_csv",
]

_Save = TypeVar("_Save", bound=Callable[..., list[Path]])

_SAVE_DOC = """Write {files} into ``directory``.

Each file is written atomically; the directory is created if needed.{note}

Parameters
----------
directory : str or path-like
figure_format : FigureFormat or str, optional
    The figure's format and resolution (default PNG,
    :class:`flexarm.figures.FigureFormat`): ``{figure}.pdf`` with ``"pdf"``.

Returns
-------
list of Path
    The files written{returns}.
"""


def save_docstring(
    files: str, figure: str, note: str = "", returns: str = ""
) -> Callable[[_Save], _Save]:
    """Give a result's ``save(directory, *, figure_format=None)`` the docstring all of
    them share: it writes ``files`` (reST), the figure ``figure`` (its stem) among them;
    ``note`` follows the first paragraph, ``returns`` the description of the result."""

    def decorate(save: _Save) -> _Save:
        note_text = f"\n{note}" if note else ""
        save.__doc__ = _SAVE_DOC.format(files=files, figure=figure, note=note_text, returns=returns)
        return save

    return decorate


def output_directory(directory: str | os.PathLike[str]) -> Path:
    """``directory`` as a path, created (with its parents) if it does not exist."""
    out = Path(directory)
    out.mkdir(parents=True, exist_ok=True)
    return out


def write_csv(path: Path, columns: Sequence[NDArray[Any]], header: str, fmt: str = "%.12g") -> Path:
    """Write ``columns`` (each of shape (n,)) as a CSV table under ``header``, atomically."""
    with atomic_path(path) as tmp:
        np.savetxt(
            tmp, np.column_stack(columns), fmt=fmt, delimiter=",", header=header, comments=""
        )
    return path


def save_axes_figure(
    plot: Callable[[Axes], Any],
    height: float,
    path: Path,
    figure_format: FigureFormat | str | None,
) -> Path:
    """Draw ``plot(ax)`` on one axes of a figure a column wide and ``height`` inches high
    (the axes in the style too), and save it as ``path`` with the format's suffix."""
    fig = new_figure(SINGLE_COLUMN, height)
    with style():  # the axes, its ticks and labels in the style too
        ax = fig.add_subplot()
    plot(ax)
    return save_figure(fig, path, figure_format)


def save_table_and_plot(
    directory: str | os.PathLike[str],
    name: str,
    table: tuple[Sequence[NDArray[Any]], str, str],
    plot: Callable[[Axes], Any],
    height: float,
    figure_format: FigureFormat | str | None,
) -> list[Path]:
    """Write ``name.csv`` (``table``: columns, header, number format) and the figure of
    ``plot`` as ``name.png`` (or the format asked for) into ``directory``."""
    out = output_directory(directory)
    columns, header, fmt = table
    csv = write_csv(out / f"{name}.csv", columns, header, fmt)
    return [csv, save_axes_figure(plot, height, out / name, figure_format)]
