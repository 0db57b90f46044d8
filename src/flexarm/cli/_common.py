"""What every ``flexarm`` command shares: errors, exit codes, JSON and output directories."""

from __future__ import annotations

import argparse
import math
import os
import secrets
import shutil
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any, NoReturn

import numpy as np

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


def json_ready(value: Any) -> Any:
    """Strict JSON: NaN and infinities become null; tuples and arrays, lists."""
    if isinstance(value, Mapping):
        return {str(k): json_ready(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [json_ready(v) for v in value]
    if isinstance(value, np.ndarray):
        return json_ready(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


@contextmanager
def output_directory(out: Path) -> Iterator[Path]:
    """Yield a fresh directory beside ``out``; on success rename it to ``out``.

    Everything written into the yielded directory appears under ``out`` at once
    (``out`` may be an empty directory, which is replaced); on any error the
    temporary directory is removed and ``out`` is left as it was.
    """
    while True:
        tmp = out.parent / f".{out.name}.{secrets.token_hex(4)}.tmp"
        try:
            tmp.mkdir()
            break
        except FileExistsError:  # pragma: no cover - 32 random bits
            continue
    try:
        yield tmp
        os.replace(tmp, out)  # atomic; replaces an empty directory
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
