"""The ``flexarm`` command line: parse, call the library, print.

One module per command (``modes``, ``simulate``, …), each with an
``add_parser(subparsers)``. Bad input ends with one line on stderr and exit
status 2, never a traceback; a job that fails (a simulation that diverges)
ends with one line on stderr and exit status 1.

Signals: Ctrl-C (SIGINT) and SIGTERM end a command with one line on stderr
("interrupted; nothing written", or what a command kept) and exit status 130
or 143; outputs are written atomically, so an interrupted command leaves no
partial or temporary file, and runs in worker threads stop at their next chunk.
A closed stdout (``flexarm modes --json | head``) ends the command quietly with
status 141.
"""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
from collections.abc import Callable, Sequence
from types import FrameType
from typing import NoReturn

from .._version import __version__
from ..errors import InvalidTypeError, InvalidValueError
from . import calibrate, identify, modes, reproduce, simulate, sweep
from ._common import (
    EXIT_INTERRUPTED,
    EXIT_PIPE,
    EXIT_TERMINATED,
    EXIT_USAGE,
    Parser,
    Stopped,
    Terminated,
    UsageError,
)

__all__ = ["build_parser", "main"]


def build_parser() -> argparse.ArgumentParser:
    """The ``flexarm`` argument parser (one subcommand per job)."""
    parser = Parser(
        prog="flexarm",
        description=(
            "Model, simulate, control and identify flexible robot manipulators. "
            "Run 'flexarm COMMAND --help' for a command's options."
        ),
        formatter_class=argparse.HelpFormatter,  # the description wrapped to the terminal
    )
    parser.add_argument("--version", action="version", version=f"flexarm {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", parser_class=Parser)
    for command in (reproduce, simulate, sweep, identify, calibrate, modes):
        command.add_parser(sub)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status."""
    parser = build_parser()
    prog = "flexarm"
    previous = _catch_sigterm()
    try:
        args = parser.parse_args(argv)
        if args.command is None:
            parser.print_help()
            return 0
        prog = f"flexarm {args.command}"
        status: int = args.func(args)
        return status
    except UsageError as exc:
        print(exc, file=sys.stderr)
        return EXIT_USAGE
    except (InvalidValueError, InvalidTypeError) as exc:
        # flexarm's own input checks; any other exception is a bug and shows its traceback
        print(f"{prog}: error: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except Stopped as exc:
        print(f"{prog}: {exc}", file=sys.stderr)
        return exc.status
    except KeyboardInterrupt:
        print(f"{prog}: interrupted; nothing written", file=sys.stderr)
        return EXIT_INTERRUPTED
    except Terminated:
        print(f"{prog}: terminated; nothing written", file=sys.stderr)
        return EXIT_TERMINATED
    except BrokenPipeError:
        _quiet_stdout()
        return EXIT_PIPE
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


_Handler = Callable[[int, FrameType | None], object] | int | signal.Handlers | None


def _catch_sigterm() -> _Handler:
    """Turn SIGTERM into :class:`Terminated` in the main thread (cleanup then runs as
    for Ctrl-C); return the previous handler (None off the main thread)."""
    if threading.current_thread() is not threading.main_thread():
        return None

    def handler(signum: int, frame: FrameType | None) -> None:
        raise Terminated

    previous: _Handler = signal.signal(signal.SIGTERM, handler)
    return signal.SIG_DFL if previous is None else previous


def _quiet_stdout() -> None:
    """Point stdout at /dev/null: the reader is gone, and the interpreter's final
    flush must not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):  # pragma: no cover - stdout without a descriptor
        pass


def _entry() -> NoReturn:  # pragma: no cover - console script shim
    sys.exit(main())
