"""Ctrl-C, SIGTERM, a closed stdout and SIGKILL, as a user's terminal delivers them:
one line, the conventional exit status, nothing half-written, nothing left behind."""

from __future__ import annotations

import os
import pty
import random
import select
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from flexarm.sim.results import RESULT_FILES, SimulationResult
from helpers.cli import as_at_a_terminal

pytestmark = pytest.mark.skipif(sys.platform != "linux", reason="POSIX signals and /dev/ptmx")
HANG = 120.0  # s: a guard against a hung child, not a timing claim


def _flexarm(*args: str, stderr_tty: bool = False) -> tuple[subprocess.Popen[bytes], int | None]:
    """Start ``python -m flexarm ARGS``; stderr on a pseudo-terminal if asked (so that
    progress is printed, as for a user at a terminal)."""
    master = None
    kw: dict[str, object] = {"stderr": subprocess.PIPE}
    if stderr_tty:
        master, slave = pty.openpty()
        kw["stderr"] = slave
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexarm", *args],
        stdout=subprocess.PIPE,
        preexec_fn=as_at_a_terminal,
        **kw,  # type: ignore[call-overload]
    )
    if stderr_tty:
        os.close(slave)
    return proc, master


def _read_until(fd: int, needle: bytes, proc: subprocess.Popen[bytes]) -> bytes:
    seen = b""
    deadline = time.monotonic() + HANG
    while needle not in seen:
        assert time.monotonic() < deadline, f"no {needle!r} from the child: {seen[-500:]!r}"
        assert proc.poll() is None, f"the child ended early: {seen[-500:]!r}"
        ready, _, _ = select.select([fd], [], [], 0.5)
        if ready:
            seen += os.read(fd, 4096)
    return seen


def _drain(fd: int) -> bytes:
    out = b""
    while True:
        ready, _, _ = select.select([fd], [], [], 0.2)
        if not ready:
            return out
        try:
            chunk = os.read(fd, 4096)
        except OSError:  # the pty's other end closed
            return out
        if not chunk:
            return out
        out += chunk


def _leftovers(parent: Path) -> list[Path]:
    return sorted(parent.glob(".*.tmp"))


def test_ctrl_c_stops_a_reproduction_at_once(tmp_path):
    out = tmp_path / "results"
    proc, fd = _flexarm(
        "reproduce",
        "--duration",
        "3",
        "--no-sensitivity",
        "--no-beyond",
        "--out",
        str(out),
        stderr_tty=True,
    )
    assert fd is not None
    _read_until(fd, b"[1/", proc)  # runs are under way
    proc.send_signal(signal.SIGINT)
    status = proc.wait(timeout=HANG)
    text = _drain(fd).decode(errors="replace").replace("\r", "\n")
    os.close(fd)
    lines = [line for line in text.splitlines() if line.strip() and not line.startswith("[")]
    assert status == 130, text
    assert lines == ["flexarm reproduce: interrupted; nothing written"], text
    assert not out.exists() and _leftovers(tmp_path) == []


def _wait_for_temporary(parent: Path, proc: subprocess.Popen[bytes]) -> Path:
    deadline = time.monotonic() + HANG
    while True:
        found = _leftovers(parent)
        if found:
            return found[0]
        assert proc.poll() is None, "the writer ended before writing"
        assert time.monotonic() < deadline, "no temporary directory appeared"
        time.sleep(0.005)


def _long_write(out: Path) -> subprocess.Popen[bytes]:
    # 1.5 million recorded rows (0.2 ms a row): seconds of writing after a few of simulating
    proc, _ = _flexarm("simulate", "--duration", "300", "--out", str(out))
    return proc


def test_sigterm_while_writing_removes_the_temporary_directory(tmp_path):
    out = tmp_path / "sim3"
    proc = _long_write(out)
    _wait_for_temporary(tmp_path, proc)
    proc.send_signal(signal.SIGTERM)
    _, err = proc.communicate(timeout=HANG)
    assert proc.returncode == 143
    assert err.decode().splitlines() == ["flexarm simulate: terminated; nothing written"]
    assert not out.exists() and _leftovers(tmp_path) == []


def test_a_killed_writer_leaves_a_whole_result_or_none(tmp_path):
    """SIGKILL at a random moment of the write: the directory is complete or absent,
    and the next write to it removes the dead writer's temporaries."""
    rng = random.Random(7)
    for trial in range(2):
        out = tmp_path / f"run{trial}"
        proc = _long_write(out)
        _wait_for_temporary(tmp_path, proc)
        time.sleep(rng.uniform(0.0, 1.5))
        proc.kill()
        proc.wait(timeout=HANG)
        if out.exists():
            assert sorted(p.name for p in out.iterdir()) == sorted(RESULT_FILES)
            SimulationResult.load(out / "result.npz")
        else:
            assert _leftovers(tmp_path)  # killed mid-write: its temporary is left...
        # ...until the next write to the same target
        again = subprocess.run(
            [sys.executable, "-m", "flexarm", "simulate", "--duration", "0.05", "--out", str(out)],
            capture_output=True,
            timeout=HANG,
        )
        assert again.returncode in (0, 2)  # 2: the complete result is never overwritten
        assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("args", [["modes", "--json"], ["simulate", "--duration", "0.05"]])
def test_a_closed_stdout_ends_quietly(args):
    proc = subprocess.Popen(
        [sys.executable, "-m", "flexarm", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader is gone before the first line
    err = proc.stderr.read()
    assert proc.wait(timeout=HANG) == 141
    assert err == b""
