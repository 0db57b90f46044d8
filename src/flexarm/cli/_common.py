"""What every ``flexarm`` command shares: errors, exit codes, JSON and output directories."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NoReturn

from .._io import json_ready, output_directory, remove_stale

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
    "check_out",
    "json_ready",
    "output_directory",
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


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, not a usage dump."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message}")


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
