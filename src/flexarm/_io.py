"""Atomic file writes: a file appears whole under its name, or not at all.

Temporary files and directories are written beside their target, named
``.{target}.{pid}.{random}.tmp``, and renamed into place when complete; on any
error (Ctrl-C and SIGTERM included) they are removed. A writer killed outright
(SIGKILL, a power cut) cannot clean up: the next write to the same target
removes the temporaries whose process is gone (:func:`remove_stale`).
"""

from __future__ import annotations

import glob
import math
import os
import secrets
import shutil
from collections.abc import Callable, Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["JSONValue", "atomic_path", "json_ready", "output_directory", "remove_stale"]

JSONValue = None | bool | int | float | str | list["JSONValue"] | dict[str, "JSONValue"]
"""A value JSON can hold (before :func:`json_ready` maps NaN and arrays)."""


@contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success rename it to ``path``.

    The temporary file is in the same directory (so the rename is atomic) and
    gets the mode a new file would get under the current umask. On any error it
    is removed and ``path`` is left untouched.
    """
    target = Path(path)
    with _temporary(target, _new_file, _remove_file) as tmp:
        yield tmp
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, target)


@contextmanager
def output_directory(out: Path) -> Iterator[Path]:
    """Yield a fresh directory beside ``out``; on success rename it to ``out``.

    Everything written into the yielded directory appears under ``out`` at once
    (``out`` may be an empty directory, which is replaced); on any error the
    temporary directory is removed and ``out`` is left as it was.
    """
    with _temporary(out, Path.mkdir, _remove_tree) as tmp:
        yield tmp
        os.replace(tmp, out)  # atomic; replaces an empty directory


@contextmanager
def _temporary(
    target: Path, create: Callable[[Path], object], remove: Callable[[Path], None]
) -> Iterator[Path]:
    """Yield a new temporary beside ``target`` (made by ``create``, which raises
    :class:`FileExistsError` if the name is taken), after removing the stale ones of
    earlier writes; on any error, in the ``with`` block too, ``remove`` it."""
    remove_stale(target)
    tmp: Path | None = None
    try:
        while True:
            # named before it is created: an interruption at any point finds it to remove
            tmp = _temporary_name(target)
            try:
                create(tmp)
                break
            except FileExistsError:  # pragma: no cover - 32 random bits and our pid
                tmp = None
        yield tmp
    except BaseException:
        if tmp is not None:
            remove(tmp)
        raise


def _temporary_name(target: Path) -> Path:
    """``.{target}.{pid}.{random}.tmp`` beside ``target`` (see the module docstring)."""
    return target.parent / f".{target.name}.{os.getpid()}.{secrets.token_hex(4)}.tmp"


def _new_file(path: Path) -> None:
    os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600))


def _remove_file(path: Path) -> None:
    path.unlink(missing_ok=True)


def _remove_tree(path: Path) -> None:
    shutil.rmtree(path, ignore_errors=True)


def remove_stale(target: Path) -> list[Path]:
    """Remove the temporaries of earlier writes to ``target`` whose process is gone
    (killed before it could clean up); return what was removed.

    Temporaries of a live process (another writer at work) are left alone.
    """
    removed: list[Path] = []
    try:
        siblings = list(target.parent.glob(f".{glob.escape(target.name)}.*.tmp"))
    except OSError:
        return removed
    for tmp in siblings:
        parts = tmp.name[len(target.name) + 2 : -len(".tmp")].split(".")
        if len(parts) < 2 or not parts[0].isdigit() or _alive(int(parts[0])):
            continue
        try:
            if tmp.is_dir() and not tmp.is_symlink():
                shutil.rmtree(tmp)
            else:
                tmp.unlink()
            removed.append(tmp)
        except OSError:
            continue
    return removed


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    except (OverflowError, OSError):
        return False
    return True


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
