"""What every ``flexarm`` command shares: errors, exit codes, JSON and output directories."""

from __future__ import annotations

import argparse
from pathlib import Path
from typing import NoReturn

from .._io import json_ready, output_directory

__all__ = [
    "EXIT_FAILURE",
    "EXIT_USAGE",
    "Parser",
    "UsageError",
    "check_out",
    "json_ready",
    "output_directory",
]

EXIT_FAILURE = 1  # the job failed (a simulation diverged), or the results could not be written
EXIT_USAGE = 2


class UsageError(Exception):
    """Bad input on the command line (exit status 2)."""


class Parser(argparse.ArgumentParser):
    """An argument parser whose errors are one line, not a usage dump."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: error: {message}")


def check_out(out: Path, prog: str) -> None:
    """Refuse an ``--out`` that cannot take the results, before any work is done.

    ``out`` must be new or an empty directory, in an existing parent directory.
    """
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
