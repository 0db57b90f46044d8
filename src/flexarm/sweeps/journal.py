"""The journal of a sweep: finished runs, appended as they finish, so a sweep resumes.

A sweep's output directory holds ``journal.jsonl``: one JSON line per finished
run (:class:`~flexarm.sweeps.records.Record`), keyed by the run's id (the hash
of its full scenario, :func:`~flexarm.sweeps.keys.run_id`). Rerunning a sweep
into the same directory skips every run the journal holds, so an interrupted
sweep picks up where it stopped, and a grown sweep (more grid values, a larger
``n``) only does its new runs.

Each line is written whole by one ``write`` to a file opened for appending: an
interruption (Ctrl-C) leaves the journal with the lines of the runs that
finished and no half line. A line cut short by a crash (the machine going
down) is not a complete line: it is ignored on reading and cut off before the
next append. Records written by another version of flexarm are not reused.

The directory also holds ``sweep.json`` (the sweep: its base scenario and each
run's id and parameters), written first, and, when the sweep completes, the
table (``runs.csv``, ``runs.parquet``) and ``summary.json``.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from types import TracebackType

from .._io import atomic_path
from .._version import __version__
from ..errors import OutputDirectoryError
from .records import Record

__all__ = [
    "JOURNAL_FILE",
    "SWEEP_FILE",
    "Journal",
    "OutputDirectoryError",
    "check_output_directory",
    "read_journal",
    "write_json",
]

JOURNAL_FILE = "journal.jsonl"
SWEEP_FILE = "sweep.json"
_FIELDS = ("run_id", "status", "message", "sim_time_s", "wall_time_s", "metrics", "flexarm")


def check_output_directory(out: Path) -> bool:
    """Whether ``out`` holds an earlier sweep (True) or is new or empty (False).

    Raises
    ------
    OutputDirectoryError
        If ``out`` is a file, a directory with other things in it, or its parent
        directory does not exist.
    """
    if out.exists():
        if not out.is_dir():
            raise OutputDirectoryError(f"{str(out)!r} exists and is not a directory")
        if not any(out.iterdir()):
            return False
        if not (out / SWEEP_FILE).is_file():
            raise OutputDirectoryError(
                f"{str(out)!r} exists and holds no sweep (no {SWEEP_FILE}): give a new or "
                "empty directory, or a sweep's directory to resume it"
            )
        return True
    if not out.parent.is_dir():
        raise OutputDirectoryError(f"the parent directory {str(out.parent)!r} does not exist")
    return False


def write_json(path: Path, data: object) -> None:
    """Write ``data`` as indented JSON, atomically."""
    with atomic_path(path) as tmp:
        tmp.write_text(json.dumps(data, indent=2) + "\n", encoding="utf-8")


def _parse(line: bytes) -> Record | None:
    try:
        data = json.loads(line)
    except ValueError:
        return None
    if not isinstance(data, dict) or any(k not in data for k in _FIELDS):
        return None
    record: Record = {k: data[k] for k in _FIELDS}  # type: ignore[assignment]
    return record


def read_journal(path: Path, version: str = __version__) -> dict[str, Record]:
    """The complete records of a journal by run id (the last of a repeated id).

    Lines cut short, lines that are not records and records of another
    ``version`` of flexarm are left out. A missing journal is empty.
    """
    try:
        data = path.read_bytes()
    except FileNotFoundError:
        return {}
    records: dict[str, Record] = {}
    for line in data.split(b"\n")[:-1]:  # the last piece has no newline: not complete
        record = _parse(line)
        if record is not None and record["flexarm"] == version:
            records[record["run_id"]] = record
    return records


class Journal:
    """A journal open for appending (a context manager).

    Parameters
    ----------
    path : path
        The journal file; created if missing. A trailing line without its
        newline (a crash during a write) is cut off first.
    """

    def __init__(self, path: str | os.PathLike[str]):
        self.path = Path(path)
        self._fd = os.open(self.path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o666)
        size = os.fstat(self._fd).st_size
        if size:
            tail = os.pread(self._fd, min(size, 1 << 16), max(0, size - (1 << 16)))
            if not tail.endswith(b"\n"):
                keep = self._last_newline(size)
                os.ftruncate(self._fd, keep)

    def _last_newline(self, size: int) -> int:
        """The length of the journal up to and including its last newline."""
        end = size
        while end > 0:
            start = max(0, end - (1 << 16))
            chunk = os.pread(self._fd, end - start, start)
            k = chunk.rfind(b"\n")
            if k >= 0:
                return start + k + 1
            end = start
        return 0

    def read(self) -> dict[str, Record]:
        """The journal's complete records by run id (:func:`read_journal`)."""
        return read_journal(self.path)

    def append(self, record: Record) -> None:
        """Append one record as one line, written whole by one ``write``."""
        line = (json.dumps(record, separators=(",", ":")) + "\n").encode()
        written = os.write(self._fd, line)
        while written < len(line):  # pragma: no cover - a short write to a regular file
            written += os.write(self._fd, line[written:])

    def close(self) -> None:
        """Flush the journal to disk and close it."""
        if self._fd >= 0:
            try:
                os.fsync(self._fd)
            finally:
                os.close(self._fd)
                self._fd = -1

    def __enter__(self) -> Journal:
        return self

    def __exit__(
        self,
        exc_type: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        self.close()
