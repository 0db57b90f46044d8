"""The README's examples run as written, in order, with the output they show.

* The first two ``bash`` blocks are the two commands (the contract with ``.ci/run``).
* Every ``python`` block runs in order in one namespace, as a reader would type them.
* Every later ``bash`` block (the tour's command lines) runs in order in one temporary
  directory with this interpreter's ``flexarm``; each command exits 0, or with the status
  its comment states (``# exits 2``). The documentation's build command is not run here
  (``tests/test_docs.py`` builds the same sources the same way): its form is checked.
* A ``text`` block right after a ``python`` or ``bash`` block is the output it claims:
  each of its lines must appear in what the block printed (stdout and stderr, runs of
  blanks counted as one).
"""

from __future__ import annotations

import contextlib
import io
import pathlib
import re
import shlex
import subprocess
import sys

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = ROOT / "README.md"
CI = ROOT / ".ci" / "run"
TEXT = README.read_text()
# every fenced block in order: (language, body, the text block right after it or None)
FENCE = re.compile(r"```(\w*)\n(.*?)```(?:\s*```text\n(.*?)```)?", flags=re.S)
BLOCKS = [(m[1], m[2], m[3]) for m in FENCE.finditer(TEXT) if m[1] != "text"]
COMMANDS = re.findall(r"```bash\n(.*?)\n```", TEXT, flags=re.S)
PYTHON = [(body, shown) for lang, body, shown in BLOCKS if lang == "python"]
TOUR = [(body, shown) for lang, body, shown in BLOCKS if lang == "bash"][2:]


def _squeeze(text: str) -> str:
    return " ".join(text.split())


def _check_shown(shown: str | None, printed: str, where: str) -> None:
    lines = [_squeeze(ln) for ln in (shown or "").splitlines() if ln.strip()]
    got = [_squeeze(ln) for ln in printed.splitlines()]
    missing = [ln for ln in lines if not any(ln in g for g in got)]
    assert not missing, f"{where}: shown but not printed: {missing}\nprinted:\n{printed}"


def test_the_two_commands_are_the_contract():
    """The README's first command installs and runs ``flexarm reproduce``; its second
    installs the test extra and runs pytest, and is exactly what .ci/run executes."""
    install_and_run, install_and_test = COMMANDS[0], COMMANDS[1]
    assert "pip install -e ." in install_and_run and install_and_run.endswith("flexarm reproduce")
    assert ".[test]" in install_and_test and install_and_test.endswith("-m pytest")
    ci_lines = [ln.strip() for ln in CI.read_text().splitlines()]
    assert install_and_test in ci_lines


def test_the_readme_shows_what_the_tests_check():
    """The parsing above finds the tour: Python with its output, command lines with
    theirs, one of them failing on purpose, and the documentation's build command."""
    assert len(PYTHON) >= 1 and any(shown for _, shown in PYTHON)
    assert len(TOUR) >= 3 and any(shown for _, shown in TOUR)
    assert any("# exits" in body for body, _ in TOUR)
    assert any("sphinx-build" in body for body, _ in TOUR)


def test_readme_examples_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the examples write files
    namespace: dict[str, object] = {}
    for block, shown in PYTHON:  # later blocks use names from earlier ones, as a reader would
        out = io.StringIO()
        try:
            with contextlib.redirect_stdout(out):
                exec(compile(block, str(README), "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"README example failed: {exc!r}\n{block}")
        _check_shown(shown, out.getvalue(), f"README example\n{block}")
    import matplotlib.pyplot as plt

    plt.close("all")


def _expected_status(line: str) -> int:
    found = re.search(r"#.*\bexits (\d+)", line)
    return int(found[1]) if found else 0


def test_readme_command_lines_run(tmp_path):
    """The tour's commands, in order, in one directory, with the status and output shown."""
    for body, shown in TOUR:
        if "sphinx-build" in body:  # built by tests/test_docs.py with the same options
            assert '-e ".[docs]"' in body
            assert "sphinx-build -W --keep-going -b html docs docs/_build/html" in body
            continue
        printed = ""
        for line in body.splitlines():
            command = line.split("#", 1)[0].strip()
            if not command:
                continue
            argv = shlex.split(command)
            assert argv[0] == "flexarm", f"the tour runs flexarm commands only: {line}"
            res = subprocess.run(
                [sys.executable, "-m", "flexarm", *argv[1:]],
                cwd=tmp_path,
                capture_output=True,
                text=True,
                timeout=300,
                check=False,
            )
            want = _expected_status(line)
            assert res.returncode == want, (
                f"{command}: exit {res.returncode}, README says {want}\n{res.stdout}{res.stderr}"
            )
            printed += res.stdout + res.stderr
        _check_shown(shown, printed, body)
