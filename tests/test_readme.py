"""The README's Python examples run as written."""

from __future__ import annotations

import pathlib
import re

import pytest

README = pathlib.Path(__file__).resolve().parents[1] / "README.md"
BLOCKS = re.findall(r"```python\n(.*?)```", README.read_text(), flags=re.S)


CI = pathlib.Path(__file__).resolve().parents[1] / ".ci" / "run"
COMMANDS = re.findall(r"```bash\n(.*?)\n```", README.read_text(), flags=re.S)


def test_the_two_commands_are_the_contract():
    """The README's first command installs and runs ``flexarm reproduce``; its second
    installs the test extra and runs pytest, and is exactly what .ci/run executes."""
    install_and_run, install_and_test = COMMANDS[0], COMMANDS[1]
    assert "pip install -e ." in install_and_run and install_and_run.endswith("flexarm reproduce")
    assert ".[test]" in install_and_test and install_and_test.endswith("-m pytest")
    ci_lines = [ln.strip() for ln in CI.read_text().splitlines()]
    assert install_and_test in ci_lines


def test_readme_examples_run(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the examples write files
    namespace: dict[str, object] = {}
    for block in BLOCKS:  # later blocks use names from earlier ones, as a reader would
        try:
            exec(compile(block, str(README), "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"README example failed: {exc!r}\n{block}")
    import matplotlib.pyplot as plt

    plt.close("all")
