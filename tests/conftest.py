"""The Hypothesis profiles, and checks shared by the tests of figures
(``test_figures.py``, ``test_report.py``)."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
from hypothesis import settings

# "ci" (the default): the same examples on every run, so a run fails only for a change
# (what a fresh random search found once is kept as an explicit @example). "explore":
# a new random search each run, to look for more: HYPOTHESIS_PROFILE=explore pytest ...
settings.register_profile("ci", derandomize=True)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))


def pytest_sessionstart(session):
    """Under pytest-xdist, compile the kernels nearly every test calls into Numba's
    on-disk cache before the workers start, in parallel shares
    (``helpers/warm_up.py``): from a cold cache the workers would each compile them,
    at the same time. Nothing is done in a worker or without xdist; a failed share
    costs only time (the tests then compile what they call)."""
    config = session.config
    if hasattr(config, "workerinput") or not config.pluginmanager.has_plugin("dsession"):
        return
    script = Path(__file__).parent / "helpers" / "warm_up.py"
    subprocess.run([sys.executable, str(script)], check=False)


UNIT = re.compile(r"^\S.* \([^()]+\)$")  # "quantity (unit)"; "(-)" when dimensionless
SMALLEST_FONT = 6.0  # points: the least a printed figure may carry


def _axes_to_label(ax):
    """The axis names ("x", "y", "z") ``ax`` must label: a colour bar labels its long
    axis only."""
    bar = getattr(ax, "_colorbar", None)
    if bar is not None:
        return ["y" if bar.orientation == "vertical" else "x"]
    return ["x", "y", "z"] if ax.name == "3d" else ["x", "y"]


def _label(ax, name):
    """The label of axis ``name`` of ``ax``, or of a sibling sharing it (a shared axis
    is labelled once, under the bottom panel)."""
    text = getattr(ax, f"get_{name}label")()
    if text or name == "z":
        return text
    for other in getattr(ax, f"get_shared_{name}_axes")().get_siblings(ax):
        if getattr(other, f"get_{name}label")():
            return getattr(other, f"get_{name}label")()
    return text


def _assert_readable(fig, width=None):
    """Every axis of every axes labelled "quantity (unit)" (insets excepted: they
    enlarge their parent's axes); no visible text below 6 pt; the figure as wide as a
    paper's column or two (``width``, inches) when flexarm made it."""
    from matplotlib.text import Text

    assert fig.axes, "an empty figure"
    for ax in fig.axes:
        for name in _axes_to_label(ax):
            text = _label(ax, name)
            assert UNIT.match(text), f"{name}-axis of {ax.get_title()!r}: {text!r}"
    small = [
        (t.get_text(), t.get_fontsize())
        for t in fig.findobj(Text)
        if t.get_visible() and t.get_text() and t.get_fontsize() < SMALLEST_FONT
    ]
    assert not small, small
    if width is not None:
        assert fig.get_size_inches()[0] == pytest.approx(width)


def _root(artist):
    """The figure an axes is drawn in (through subfigures)."""
    from matplotlib.figure import Figure

    fig = artist.figure
    while not isinstance(fig, Figure):
        fig = fig.figure
    return fig


@pytest.fixture
def assert_readable():
    """``assert_readable(fig, width=None)``: what a reader of a printed figure needs."""
    return _assert_readable


@pytest.fixture
def root():
    """``root(ax)``: the figure an axes is drawn in."""
    return _root
