"""The user guide's Python examples run as written, page by page, in order."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

GUIDE = Path(__file__).resolve().parents[1] / "docs" / "guide"
PAGES = sorted(GUIDE.glob("*.md"))


def _blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


def test_the_guide_has_its_pages():
    names = {p.stem for p in PAGES}
    assert {"model", "simulation", "control", "identification", "validity"} <= names
    assert sum(len(_blocks(p)) for p in PAGES) >= 20


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.stem)
def test_guide_examples_run(page, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # the examples write files
    namespace: dict[str, object] = {}
    for block in _blocks(page):  # later blocks use names from earlier ones, as a reader would
        try:
            exec(compile(block, str(page), "exec"), namespace)
        except Exception as exc:  # pragma: no cover - the failure message is the point
            pytest.fail(f"{page.name}: example failed: {exc!r}\n{block}")
    import matplotlib.pyplot as plt

    plt.close("all")
