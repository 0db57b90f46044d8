"""What the command-line tests share: ``flexarm`` run in this process, and strict JSON."""

from __future__ import annotations

import contextlib
import io
import json
import signal
from typing import Any

import pytest

from flexarm.cli import main

__all__ = ["as_at_a_terminal", "error_line", "help_text", "run", "run_captured", "strict_json"]


def run(capsys: Any, *argv: object) -> tuple[int, str, str]:
    """``flexarm ARGV`` in this process (each argument as ``str``): the exit status and
    what it wrote to stdout and stderr (read through pytest's ``capsys``)."""
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def run_captured(*argv: object) -> tuple[int, str, str]:
    """:func:`run` without ``capsys`` (for a fixture wider than one test): the streams
    redirected into strings."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        status = main([str(a) for a in argv])
    return status, out.getvalue(), err.getvalue()


def strict_json(text: str) -> Any:
    """Parse JSON, refusing NaN and Infinity (not JSON)."""

    def refuse(name: str) -> Any:
        raise ValueError(f"non-standard JSON constant {name}")

    return json.loads(text, parse_constant=refuse)


def help_text(capsys: Any, *argv: object) -> str:
    """What ``flexarm ARGV --help`` prints to stdout; it must exit with status 0."""
    with pytest.raises(SystemExit) as exc:
        main([*(str(a) for a in argv), "--help"])
    assert exc.value.code == 0
    out: str = capsys.readouterr().out
    return out


def error_line(err: str) -> str:
    """The one line a refused command writes to stderr (asserted: one line, no traceback)."""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    return lines[0]


def as_at_a_terminal() -> None:
    """``preexec_fn`` of a command a test interrupts: Ctrl-C handled as at a terminal.
    A suite started in the background inherits SIGINT ignored (POSIX shells do that to
    background jobs), and Python then leaves it ignored in the child."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
