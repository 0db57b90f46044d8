"""The ``flexarm`` command line: parse, call the library, print.

One module per command (``modes``, ``simulate``, …), each with an
``add_parser(subparsers)``. Bad input ends with one line on stderr and exit
status 2, never a traceback; a job that fails (a simulation that diverges)
ends with one line on stderr and exit status 1.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from typing import NoReturn

from .._version import __version__
from ..errors import InvalidTypeError, InvalidValueError
from . import identify, modes, reproduce, simulate, sweep
from ._common import EXIT_USAGE, Parser, UsageError

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``flexarm`` argument parser (one subcommand per job)."""
    parser = Parser(
        prog="flexarm",
        description=(
            "Model, simulate, control and identify flexible robot manipulators. "
            "Run 'flexarm COMMAND --help' for a command's options."
        ),
    )
    parser.add_argument("--version", action="version", version=f"flexarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for command in (reproduce, simulate, sweep, identify, modes):
        command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 0
        status: int = args.func(args)
        return status
    except UsageError as exc:
        print(exc, file=sys.stderr)
        return EXIT_USAGE
    except (InvalidValueError, InvalidTypeError) as exc:
        # flexarm's own input checks; any other exception is a bug and shows its traceback
        print(f"flexarm: error: {exc}", file=sys.stderr)
        return EXIT_USAGE


def _entry() -> NoReturn:  # pragma: no cover - console script shim
    sys.exit(main())
