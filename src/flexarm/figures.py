"""Figures fit for a paper: one file format and resolution, one style, sizes for a column.

Every figure flexarm writes goes through :func:`save_figure` (atomically, in the
format of a :class:`FigureFormat`: PNG, PDF or SVG at a resolution in dpi), and
every plot draws inside :func:`style`: fonts of 7-8 pt, thin lines and a
colour-blind-safe palette (Okabe and Ito), so that a figure drawn at
:data:`SINGLE_COLUMN` or :data:`DOUBLE_COLUMN` width reads at the size it is
printed. The style is applied to what flexarm draws, never to Matplotlib's
global settings; your own plots can use it too:

>>> from flexarm.figures import DOUBLE_COLUMN, FigureFormat, new_figure, style
>>> FigureFormat("pdf", dpi=300).suffix
'.pdf'
>>> with style():
...     fig = new_figure(DOUBLE_COLUMN, 2.5)
...     ax = fig.add_subplot()
...     _ = ax.plot([0.0, 1.0], [0.0, 2.0])
...     _ = ax.set(xlabel="t (s)", ylabel="x (m)")

Axis labels follow one notation, ``"quantity (unit)"``: ``"x (m)"``,
``"torque (N m)"``, ``"ks (-)"`` for a dimensionless quantity.

Matplotlib is imported when a figure is drawn or saved, not with this module.
"""

from __future__ import annotations

import io
import os
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from functools import wraps
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, BinaryIO, ParamSpec, TypeVar

from ._io import atomic_path
from ._validation import check_real
from .errors import InvalidTypeError, InvalidValueError

if TYPE_CHECKING:
    from matplotlib.figure import Figure

__all__ = [
    "COLORS",
    "DEFAULT_DPI",
    "DOUBLE_COLUMN",
    "DPI_RANGE",
    "FORMATS",
    "MIME_TYPES",
    "SINGLE_COLUMN",
    "STYLE",
    "FigureFormat",
    "check_dpi",
    "figure_bytes",
    "new_figure",
    "save_figure",
    "style",
    "styled",
]

FORMATS = ("png", "pdf", "svg")
"""File formats of figures: a raster image, and two vector ones."""
MIME_TYPES = MappingProxyType(
    {"png": "image/png", "pdf": "application/pdf", "svg": "image/svg+xml"}
)
"""Media type of each format (for embedding in HTML)."""
DEFAULT_DPI = 200.0
"""Resolution of PNG figures by default, dots per inch: a double-column figure is
1400 pixels wide, sharp on a high-density screen and in a draft print."""
DPI_RANGE = (20.0, 1200.0)
"""Accepted resolutions, dpi: 1200 is the most a journal asks for line art (a
double-column figure is then 8400 pixels wide)."""
SINGLE_COLUMN = 3.5
"""Width of a figure set in one column of a two-column paper, inches."""
DOUBLE_COLUMN = 7.0
"""Width of a figure set across both columns (or in a one-column report), inches."""

COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442")
"""Colour cycle: Okabe and Ito's palette (distinguishable with every common colour
vision deficiency), without its black, which draws references and measurements."""

STYLE: Mapping[str, object] = MappingProxyType(
    {
        "font.size": 8.0,
        "axes.titlesize": 8.0,
        "axes.labelsize": 8.0,
        "xtick.labelsize": 7.0,
        "ytick.labelsize": 7.0,
        "legend.fontsize": 7.0,
        "legend.title_fontsize": 7.0,
        "figure.titlesize": 9.0,
        "axes.linewidth": 0.6,
        "axes.titlepad": 4.0,
        "axes.labelpad": 2.0,
        "axes.formatter.limits": (-3, 4),
        "axes.formatter.use_mathtext": True,
        "lines.linewidth": 1.0,
        "lines.markersize": 4.0,
        "patch.linewidth": 0.6,
        "grid.linewidth": 0.4,
        "xtick.major.width": 0.6,
        "ytick.major.width": 0.6,
        "xtick.minor.width": 0.4,
        "ytick.minor.width": 0.4,
        "xtick.major.size": 3.0,
        "ytick.major.size": 3.0,
        "xtick.minor.size": 1.5,
        "ytick.minor.size": 1.5,
        "xtick.major.pad": 2.0,
        "ytick.major.pad": 2.0,
        "legend.frameon": True,
        "legend.framealpha": 0.85,
        "legend.edgecolor": "0.8",
        "legend.handlelength": 1.8,
        "legend.borderaxespad": 0.3,
        "legend.borderpad": 0.3,
        "legend.labelspacing": 0.3,
        "image.cmap": "viridis",
        "pdf.fonttype": 42,  # TrueType in PDF: what journals' checkers ask for
        "ps.fonttype": 42,
        "svg.hashsalt": "flexarm",  # the same figure gives the same SVG
        "figure.constrained_layout.h_pad": 0.03,
        "figure.constrained_layout.w_pad": 0.03,
    }
)
"""Matplotlib settings of every flexarm figure (applied by :func:`style`; the colour
cycle is :data:`COLORS`)."""

_METADATA: Mapping[str, Mapping[str, None]] = MappingProxyType(
    {"png": {}, "pdf": {"CreationDate": None}, "svg": {"Date": None}}
)
"""No creation date in the files: the same figure gives the same bytes."""

P = ParamSpec("P")
R = TypeVar("R")


@dataclass(frozen=True)
class FigureFormat:
    """The file format and resolution of the figures a command or a ``save`` writes.

    Parameters
    ----------
    format : {"png", "pdf", "svg"}, default "png"
        File format (case-insensitive): PNG is a raster image; PDF and SVG are
        vector graphics, sharp at any size (their ``dpi`` applies only to what
        must be rasterised).
    dpi : float, default :data:`DEFAULT_DPI`
        Resolution, dots per inch, within :data:`DPI_RANGE`.

    Examples
    --------
    >>> FigureFormat("SVG").filename("tracking")
    'tracking.svg'
    >>> FigureFormat(dpi=5)
    Traceback (most recent call last):
    ...
    flexarm.errors.InvalidValueError: The 'dpi' parameter of FigureFormat must be \
between 20 and 1200. Got 5.0 instead.
    """

    format: str = "png"
    dpi: float = DEFAULT_DPI

    def __post_init__(self) -> None:
        if not isinstance(self.format, str):
            raise InvalidTypeError(
                "The 'format' parameter of FigureFormat must be a str, one of "
                f"{', '.join(FORMATS)}. Got {self.format!r} instead."
            )
        fmt = self.format.lower()
        if fmt not in FORMATS:
            raise InvalidValueError(
                "The 'format' parameter of FigureFormat must be one of "
                f"{', '.join(FORMATS)}. Got {self.format!r} instead."
            )
        object.__setattr__(self, "format", fmt)
        object.__setattr__(self, "dpi", check_dpi(self.dpi, "FigureFormat"))

    @property
    def suffix(self) -> str:
        """The file-name suffix: ``".png"``, ``".pdf"`` or ``".svg"``."""
        return f".{self.format}"

    @property
    def mime_type(self) -> str:
        """The media type: ``"image/png"``, ``"application/pdf"``, ``"image/svg+xml"``."""
        return MIME_TYPES[self.format]

    def filename(self, stem: str) -> str:
        """``stem`` with this format's suffix (``"tracking"`` -> ``"tracking.pdf"``)."""
        return f"{stem}{self.suffix}"

    @classmethod
    def coerce(cls, value: FigureFormat | str | None) -> FigureFormat:
        """A :class:`FigureFormat` from itself, a format name, or ``None`` (the default)."""
        if value is None:
            return cls()
        if isinstance(value, FigureFormat):
            return value
        if isinstance(value, str):
            return cls(value)
        raise InvalidTypeError(
            "The 'figure_format' parameter must be a FigureFormat, one of "
            f"{', '.join(FORMATS)} or None. Got {type(value).__name__} instead."
        )


def check_dpi(value: object, owner: str) -> float:
    """``value`` as a resolution in :data:`DPI_RANGE`, dpi, or raise naming ``owner``."""
    dpi = check_real(value, "dpi", owner)
    lo, hi = DPI_RANGE
    if not lo <= dpi <= hi:
        raise InvalidValueError(
            f"The 'dpi' parameter of {owner} must be between {lo:g} and {hi:g}. "
            f"Got {dpi!r} instead."
        )
    return dpi


@contextmanager
def style() -> Iterator[None]:
    """Draw inside flexarm's style (:data:`STYLE`, :data:`COLORS`); Matplotlib's global
    settings are restored on exit.

    Fonts, line widths and colours are fixed when an artist is created, so a
    figure drawn inside keeps the style when it is saved or shown later.
    """
    import matplotlib as mpl
    from cycler import cycler

    rc: Any = {**STYLE, "axes.prop_cycle": cycler(color=list(COLORS))}
    with mpl.rc_context(rc):
        yield


def styled(plot: Callable[P, R]) -> Callable[P, R]:
    """Decorate a plotting function or method: it draws inside :func:`style`."""

    @wraps(plot)
    def draw(*args: P.args, **kwargs: P.kwargs) -> R:
        with style():
            return plot(*args, **kwargs)

    return draw


def new_figure(width: float = DOUBLE_COLUMN, height: float | None = None) -> Figure:
    """A new figure in flexarm's style, not registered with pyplot (nothing global).

    Parameters
    ----------
    width : float, default :data:`DOUBLE_COLUMN`
        Inches: :data:`SINGLE_COLUMN` or :data:`DOUBLE_COLUMN` for a paper.
    height : float, optional
        Inches (default: ``0.62 width``, about the golden ratio).

    Returns
    -------
    matplotlib.figure.Figure
        With constrained layout and an Agg canvas: ``fig.savefig`` works, and
        a notebook shows it when it is the cell's value.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    w = check_real(width, "width", "new_figure", positive=True)
    h = 0.62 * w if height is None else check_real(height, "height", "new_figure", positive=True)
    with style():
        fig = Figure(figsize=(w, h), layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def save_figure(
    fig: Figure, path: str | os.PathLike[str], figure_format: FigureFormat | str | None = None
) -> Path:
    """Write ``fig`` to ``path`` with the format's suffix, atomically; return the path.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure (drawn at its own size, in inches).
    path : str or path-like
        The file; its suffix, if any, is replaced by the format's
        (``out / "tracking"`` -> ``out / "tracking.pdf"``).
    figure_format : FigureFormat or str, optional
        Format and resolution (default PNG at :data:`DEFAULT_DPI`).

    Returns
    -------
    pathlib.Path
        The file written (whole, or not at all: ``flexarm._io.atomic_path``).
    """
    fmt = FigureFormat.coerce(figure_format)
    target = Path(path).with_suffix(fmt.suffix)
    with atomic_path(target) as tmp, open(tmp, "wb") as fh:
        _print(fig, fh, fmt)
    return target


def figure_bytes(fig: Figure, figure_format: FigureFormat | str | None = None) -> bytes:
    """The bytes of the file :func:`save_figure` would write (for embedding)."""
    buf = io.BytesIO()
    _print(fig, buf, FigureFormat.coerce(figure_format))
    return buf.getvalue()


def _print(fig: Figure, fh: BinaryIO, fmt: FigureFormat) -> None:
    with style():
        fig.savefig(fh, format=fmt.format, dpi=fmt.dpi, metadata=dict(_METADATA[fmt.format]))
