"""What the ``flexarm identify`` subcommands share: parsing helpers, error mapping, output."""

from __future__ import annotations

import argparse
import json
import os
import sys
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

from ..errors import InvalidTypeError, InvalidValueError
from ..figures import FigureFormat
from ..ident.options import BANDWIDTH_RULES
from ._common import (
    EXIT_FAILURE,
    Parser,
    UsageError,
    check_out,
    figure_format,
    json_ready,
    number,
    output_directory,
    word_or_number,
    write_failed,
)

__all__ = [
    "CommandParser",
    "given",
    "library_errors",
    "output_options",
    "parse_bandwidth",
    "positive_int",
    "report",
]


class CommandParser(Parser):
    """A subcommand's parser: one-line errors, and unknown options named by the subcommand."""

    def parse_known_args(  # type: ignore[override]
        self, args: Any = None, namespace: Any = None
    ) -> tuple[argparse.Namespace, list[str]]:
        ns, extras = super().parse_known_args(args, namespace)
        if extras:
            self.error(f"unrecognized arguments: {' '.join(extras)}")
        return ns, extras


@contextmanager
def library_errors(prog: str) -> Iterator[None]:
    """Turn flexarm's own validation errors into one-line usage errors of ``prog``.

    Only :class:`~flexarm.errors.InvalidValueError` and
    :class:`~flexarm.errors.InvalidTypeError` (data-file errors included): any
    other exception is a bug and keeps its traceback.
    """
    try:
        yield
    except (InvalidValueError, InvalidTypeError) as exc:
        raise UsageError(f"{prog}: error: {exc}") from None


parse_bandwidth = word_or_number(
    BANDWIDTH_RULES, f"a number or one of {', '.join(BANDWIDTH_RULES)}"
)
"""``--bandwidth``: a number (checked by the library) or a rule name."""


def positive_int(minimum: int) -> Callable[[str], int]:
    """An ``argparse`` type: an integer ``>= minimum``."""
    parse = number(integer=True, minimum=minimum)

    def as_int(text: str) -> int:
        return int(parse(text))

    return as_int


def given(args: argparse.Namespace, *same: str, **names: str) -> dict[str, Any]:
    """``{parameter: value}`` of the options the user gave (``same``: parameters named as
    their option's dest; ``names``: parameter -> dest)."""
    dests = {**{name: name for name in same}, **names}
    return {p: getattr(args, d) for p, d in dests.items() if getattr(args, d) is not None}


def report(
    args: argparse.Namespace,
    prog: str,
    summary: dict[str, Any],
    save: Callable[[Path], list[Path]],
    text: Callable[[dict[str, Any]], str],
) -> int:
    """Write ``save``'s files and ``summary.json`` into ``--out`` (all at once), then print.

    ``summary`` gets ``out`` and ``files``; stdout gets the JSON (``--json``)
    or ``text(summary)``. Exit status 1 if the files cannot be written.
    """
    out = None if args.out is None else Path(os.path.abspath(args.out))
    summary["out"] = None if out is None else str(out)
    summary["files"] = []
    if out is not None:
        try:
            with output_directory(out) as tmp:
                names = [p.name for p in save(tmp)]
                summary["files"] = [*dict.fromkeys([*names, "summary.json"])]
                (tmp / "summary.json").write_text(json.dumps(json_ready(summary), indent=2) + "\n")
        except OSError as exc:
            print(write_failed(prog, out, exc), file=sys.stderr)
            return EXIT_FAILURE
    if args.json:
        print(json.dumps(json_ready(summary), indent=2))
    else:
        print(text(summary))
        if out is not None:
            print(f"  results in {out}: {', '.join(summary['files'])}")
    return 0


def output_options(args: argparse.Namespace, prog: str) -> FigureFormat:
    """Refuse an ``--out`` that cannot take the results, before any work, and return the
    figure format of ``--format`` and ``--dpi`` (which need ``--out``)."""
    if args.out is not None:
        check_out(Path(os.path.abspath(args.out)), prog)
    return figure_format(args, prog, args.out)
