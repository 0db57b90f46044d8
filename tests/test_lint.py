"""ruff and mypy stay clean on the sources (skipped where the tools are absent)."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _tool(name: str) -> list[str] | None:
    exe = pathlib.Path(sys.executable).with_name(name)
    if exe.exists():
        return [str(exe)]
    found = shutil.which(name)
    return [found] if found else None


TREES = ("src", "tests", "benchmarks", "examples", "docs")


def _ruff_passes(*args):
    """``ruff ARGS`` over the source trees exits with status 0 (skipped without ruff)."""
    ruff = _tool("ruff")
    if ruff is None:
        pytest.skip("ruff is not installed (pip install -e '.[test]')")
    res = subprocess.run(
        [*ruff, *args, *TREES], cwd=ROOT, capture_output=True, text=True, check=False
    )
    assert res.returncode == 0, res.stdout + res.stderr


def test_ruff_clean():
    _ruff_passes("check")


def test_ruff_format_clean():
    _ruff_passes("format", "--check")


def test_mypy_clean():
    mypy = _tool("mypy")
    if mypy is None:
        pytest.skip("mypy is not installed (pip install -e '.[test]')")
    res = subprocess.run([*mypy], cwd=ROOT, capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stdout + res.stderr
