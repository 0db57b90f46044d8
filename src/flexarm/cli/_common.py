"""What every ``flexarm`` command shares: errors, exit codes, JSON and output directories."""

from __future__ import annotations

import argparse
import errno
import math
from collections.abc import Callable, Iterable
from pathlib import Path
from typing import Any, NoReturn

from .._io import json_ready, output_directory, remove_stale
from ..errors import InvalidValueError
from ..figures import DEFAULT_DPI, DPI_RANGE, FORMATS, FigureFormat, check_dpi

__all__ = [
    "EXIT_FAILURE",
    "EXIT_INTERRUPTED",
    "EXIT_PIPE",
    "EXIT_TERMINATED",
    "EXIT_USAGE",
    "Parser",
    "Stopped",
    "Terminated",
    "UsageError",
    "add_figure_options",
    "check_out",
    "figure_format",
    "json_ready",
    "number",
    "output_directory",
    "word_or_number",
]

EXIT_FAILURE = 1  # the job failed (a simulation diverged), or the results could not be written
EXIT_USAGE = 2
EXIT_INTERRUPTED = 130  # 128 + SIGINT: Ctrl-C
EXIT_PIPE = 141  # 128 + SIGPIPE: the reader of stdout went away (e.g. `| head`)
EXIT_TERMINATED = 143  # 128 + SIGTERM


class Terminated(BaseException):
    """SIGTERM arrived (raised in the main thread by the command line's handler, so
    that cleanup runs as for Ctrl-C)."""


class Stopped(BaseException):
    """A command interrupted by Ctrl-C or SIGTERM that kept something: ``message``
    says what (the command line prints it as the one line, and exits ``status``)."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


class UsageError(Exception):
    """Bad input on the command line (exit status 2)."""


def number(
    *, positive: bool = False, nonnegative: bool = False, integer: bool = False, minimum: int = 0
) -> Callable[[str], float]:
    """An argparse ``type``: a finite number (``positive``, ``nonnegative``), or an
    integer ``>= minimum``; the parser names the option in its one-line error."""

    def parse(text: str) -> float:
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            kind = "an integer" if integer else "a number"
            raise argparse.ArgumentTypeError(f"must be {kind}. Got {text!r} instead.") from None
        if integer:
            if value < minimum:
                raise argparse.ArgumentTypeError(f"must be >= {minimum}. Got {text!r} instead.")
            return value
        if not math.isfinite(value):
            raise argparse.ArgumentTypeError(f"must be finite. Got {text!r} instead.")
        if positive and not value > 0:
            raise argparse.ArgumentTypeError(f"must be > 0. Got {text!r} instead.")
        if nonnegative and not value >= 0:
            raise argparse.ArgumentTypeError(f"must be >= 0. Got {text!r} instead.")
        return value

    return parse


def word_or_number(words: Iterable[str], expected: str) -> Callable[[str], str | float]:
    """An ``argparse`` type: one of ``words``, or a number (checked by the library);
    anything else is an error saying what is ``expected``."""
    choices = tuple(words)

    def parse(text: str) -> str | float:
        if text in choices:
            return text
        try:
            return float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {expected}. Got {text!r} instead.") from None

    return parse


def _format_option(text: str) -> str:
    if text.lower() in FORMATS:
        return text.lower()
    raise argparse.ArgumentTypeError(f"must be one of {', '.join(FORMATS)}. Got {text!r} instead.")


def _dpi_option(text: str) -> float:
    value = number(positive=True)(text)
    try:
        return check_dpi(value, "")
    except InvalidValueError:
        lo, hi = DPI_RANGE
        raise argparse.ArgumentTypeError(
            f"must be between {lo:g} and {hi:g} (dots per inch). Got {text!r} instead."
        ) from None


def add_figure_options(parser: argparse.ArgumentParser, written: str = "with --out") -> None:
    """Add ``--format png|pdf|svg`` and ``--dpi`` (the figures' file format and
    resolution, :class:`flexarm.figures.FigureFormat`) to a command that writes figures
    (``written``: when it does)."""
    lo, hi = DPI_RANGE
    parser.add_argument(
        "--format",
        type=_format_option,
        metavar="png|pdf|svg",
        help=f"file format of the figures written {written} (default png; pdf and svg are "
        "vector graphics, sharp at any size)",
    )
    parser.add_argument(
        "--dpi",
        type=_dpi_option,
        metavar="DPI",
        help=f"resolution of the figures, dots per inch (default {DEFAULT_DPI:g}; "
        f"{lo:g} to {hi:g}; for pdf and svg only what is rasterised)",
    )


def figure_format(args: argparse.Namespace, prog: str, out: object = True) -> FigureFormat:
    """The :class:`~flexarm.figures.FigureFormat` of ``--format`` and ``--dpi``;
    a usage error if either is given but no figure will be written (``out`` is None)."""
    if out is None:
        for option in ("format", "dpi"):
            if getattr(args, option) is not None:
                raise UsageError(
                    f"{prog}: error: argument --{option}: figures are written only with --out DIR"
                )
    fmt = "png" if args.format is None else args.format
    dpi = DEFAULT_DPI if args.dpi is None else args.dpi
    return FigureFormat(fmt, dpi)


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, not a usage dump, and whose
    description and epilog are printed as written (their line breaks kept), unless
    ``formatter_class`` says otherwise."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", argparse.RawDescriptionHelpFormatter)
        super().__init__(*args, **kwargs)

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message}")


def write_failed(prog: str, out: Path, exc: OSError) -> str:
    """The one line for results that could not be written into ``out``: what the
    system said, in words that say what to do."""
    reasons = {
        errno.EROFS: "the file system is read-only",
        errno.EACCES: "permission denied",
        errno.EPERM: "permission denied",
        errno.ENOSPC: "the disk is full",
        errno.EDQUOT: "the disk quota is exceeded",
        errno.EBUSY: "it is a mount point or in use (choose a new directory inside it)",
        errno.EXDEV: "it is on another file system than its parent directory",
    }
    reason = reasons.get(exc.errno or 0, exc.strerror or str(exc))
    return f"{prog}: error: cannot write the results into {str(out)!r}: {reason}; nothing written"


def check_out(out: Path, prog: str) -> None:
    """Refuse an ``--out`` that cannot take the results, before any work is done.

    ``out`` must be new or an empty directory, in an existing parent directory.
    Temporaries of earlier writes to ``out`` whose process was killed are removed
    first (:func:`flexarm._io.remove_stale`).
    """
    remove_stale(out)
    if out.exists() and not (out.is_dir() and not any(out.iterdir())):
        raise UsageError(
            f"{prog}: error: argument --out: {str(out)!r} exists and is not an empty "
            "directory (results are never overwritten)"
        )
    parent = out.parent
    if not parent.is_dir():
        raise UsageError(
            f"{prog}: error: argument --out: the parent directory {str(parent)!r} does not exist"
        )
