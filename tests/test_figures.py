"""Figures fit for a paper (:mod:`flexarm.figures`): the file formats and their bytes,
the style kept out of Matplotlib's globals, and every library plot checked for what
a reader needs — every axis labelled "quantity (unit)", fonts readable at the column
width the figure is drawn for, no cloud of thousands of overplotted points, and axes
that span the run."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib as mpl
import numpy as np
import pytest
from matplotlib.collections import PolyCollection

import flexarm as fa
from flexarm.figures import (
    DEFAULT_DPI,
    DOUBLE_COLUMN,
    SINGLE_COLUMN,
    FigureFormat,
    figure_bytes,
    new_figure,
    save_figure,
    style,
)

MAGIC = {"png": b"\x89PNG\r\n\x1a\n", "pdf": b"%PDF-", "svg": b"<?xml"}


# ------------------------------------------------------------------ the format
def test_figure_format_defaults_and_names():
    fmt = FigureFormat()
    assert (fmt.format, fmt.dpi, fmt.suffix, fmt.mime_type) == (
        "png",
        DEFAULT_DPI,
        ".png",
        "image/png",
    )
    assert FigureFormat("PDF", 300).format == "pdf" and FigureFormat("svg").filename("a") == "a.svg"
    assert FigureFormat.coerce(None) == fmt and FigureFormat.coerce("svg") == FigureFormat("svg")
    assert FigureFormat.coerce(fmt) is fmt


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"format": "jpg"}, ValueError, "'format' parameter of FigureFormat must be one of png"),
        ({"format": ".png"}, ValueError, "Got '.png'"),
        ({"format": 3}, TypeError, "'format' parameter of FigureFormat must be a str"),
        ({"dpi": 0}, ValueError, "'dpi' parameter of FigureFormat must be between 20 and 1200"),
        ({"dpi": 5000}, ValueError, "Got 5000.0 instead"),
        ({"dpi": float("nan")}, ValueError, "'dpi'.*finite"),
        ({"dpi": "300"}, TypeError, "'dpi'.*real number"),
        ({"dpi": True}, TypeError, "'dpi'"),
    ],
)
def test_bad_figure_formats(kwargs, error, match):
    with pytest.raises(error, match=match):
        FigureFormat(**kwargs)


def test_coerce_refuses_other_types():
    with pytest.raises(TypeError, match="'figure_format' parameter must be a FigureFormat"):
        FigureFormat.coerce(300)


def small_figure():
    with style():
        fig = new_figure(SINGLE_COLUMN, 2.0)
        ax = fig.add_subplot()
        ax.plot([0.0, 1.0], [0.0, 1.0])
        ax.set(xlabel="t (s)", ylabel="x (m)")
    return fig


@pytest.mark.parametrize("fmt", ["png", "pdf", "svg"])
def test_save_figure_writes_each_format_atomically_and_reproducibly(tmp_path, fmt):
    fig = small_figure()
    path = save_figure(fig, tmp_path / "a.png", FigureFormat(fmt, 100))
    assert path == tmp_path / f"a.{fmt}"  # the suffix follows the format
    data = path.read_bytes()
    assert data.startswith(MAGIC[fmt])
    assert data == figure_bytes(fig, FigureFormat(fmt, 100))  # no date: the same bytes
    assert [p.name for p in tmp_path.iterdir()] == [path.name]  # no temporary left
    if fmt == "png":  # the pixel size is the figure's size times the resolution
        width = int.from_bytes(data[16:20], "big")
        assert width == round(SINGLE_COLUMN * 100)


def test_a_save_that_fails_halfway_leaves_nothing(tmp_path, monkeypatch):
    fig = small_figure()

    def half(fh, **kwargs):
        fh.write(b"%PDF-1.4 half a file")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(fig, "savefig", half)
    with pytest.raises(OSError, match="No space"):
        save_figure(fig, tmp_path / "a", "pdf")
    assert list(tmp_path.iterdir()) == []


def test_the_style_stays_inside_the_plot():
    before = dict(mpl.rcParams)
    small_figure()
    with style():
        assert mpl.rcParams["font.size"] == 8.0
    assert dict(mpl.rcParams) == before


# ------------------------------------------------------------------ library plots
@pytest.fixture(scope="module")
def run():
    from flexarm.control.controllers import JacobianTransposePD
    from flexarm.control.trajectories import Square

    arm = fa.FlexibleArm.paper()
    return fa.simulate(arm, JacobianTransposePD.from_arm(arm), Square(), duration=0.3)


def test_simulation_plot(run, assert_readable):
    fig = run.plot()
    assert_readable(fig, DOUBLE_COLUMN)
    xy, err, _ = fig.axes
    assert xy.get_title().startswith("controller pd,")  # the name it has on the command line
    # the square's corners come after this 0.3 s run: they no longer stretch the time axis
    assert err.get_xlim()[1] < 0.5


def test_simulation_write_in_another_format(run, tmp_path):
    from flexarm.sim.results import RESULT_FILES, result_files

    assert result_files() == RESULT_FILES
    out = run.write(tmp_path / "svg", {"ok": True}, figure_format=FigureFormat("svg", 72))
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(result_files("svg")) and "tracking.svg" in names
    assert (out / "tracking.svg").read_bytes().startswith(MAGIC["svg"])


def test_regression_fit_draws_a_density_not_a_cloud(assert_readable, root):
    from flexarm.ident import fit_regression

    rng = np.random.default_rng(1)
    x = rng.uniform(-1, 1, 3000)
    many = fit_regression(x, np.tanh(2 * x) + 0.05 * rng.standard_normal(3000), grid=64)
    ax = many.plot()
    assert_readable(root(ax), SINGLE_COLUMN)
    assert any(isinstance(c, PolyCollection) for c in ax.collections)  # the hexagonal bins
    assert max(len(line.get_xdata()) for line in ax.get_lines()) <= 64  # no sample drawn
    few = fit_regression(x[:200], np.tanh(2 * x[:200]), grid=16).plot()
    assert [len(line.get_xdata()) for line in few.get_lines()] == [200, 16]  # points and m_n


def test_hammerstein_fit_and_bands(assert_readable, root):
    from flexarm.ident import fit_hammerstein, simulate_hammerstein
    from flexarm.ident.hammerstein.bootstrap import Bands
    from flexarm.ident.hammerstein.systems import Saturation

    rng = np.random.default_rng(2)
    u = rng.uniform(-2, 2, 2500)
    y = simulate_hammerstein(Saturation(1.0), [0.5], [1.0, 0.3], u, 0.05, rng=rng)
    res = fit_hammerstein(u, y, n_lags=12)
    fig = res.plot()
    assert_readable(fig, DOUBLE_COLUMN)
    free_run = fig.axes[2]
    # a window of the free run beside the measurement, not 2000 overplotted samples
    assert all(len(line.get_xdata()) <= 200 for line in free_run.get_lines())
    assert "of 2500 samples" in free_run.get_title()
    grid, k = np.linspace(-2, 2, 9), np.arange(5.0)
    bands = Bands(grid, grid, grid - 1, grid + 1, k, k - 1, k + 1, 0.9, 10, 50, "white")
    assert_readable(bands.plot(), DOUBLE_COLUMN)


def test_convergence_study_plot(assert_readable, root):
    from flexarm.ident import convergence_study

    ax = convergence_study("smooth", n=[50, 100, 200], repetitions=2, rng=0).plot()
    assert_readable(root(ax), SINGLE_COLUMN)
    assert [t.get_text() for t in ax.get_xticklabels()] == ["50", "100", "200"]


def test_fuzzy_surface_in_3d_and_as_contours(assert_readable, root):
    from flexarm.fuzzy import paper_system, plot_surface

    ax, _ = plot_surface(paper_system(), n=11)
    assert_readable(root(ax), SINGLE_COLUMN)
    with style():
        flat = new_figure(SINGLE_COLUMN, 2.8).add_subplot()
    plot_surface(paper_system(), ax=flat, n=11)
    assert_readable(root(flat))  # the colour bar is labelled λ (-)


# ------------------------------------------------------------------ the command line
def _data(path):
    rng = np.random.default_rng(4)
    u = rng.uniform(-2, 2, 600)
    y = np.convolve(np.tanh(u), [1.0, 0.5, 0.25])[:600] + 0.01 * rng.standard_normal(600)
    path.write_text("u,y\n" + "".join(f"{a:.17g},{b:.17g}\n" for a, b in zip(u, y, strict=True)))
    return str(path)


@pytest.mark.parametrize(
    ("argv", "figure", "fmt"),
    [
        (["simulate", "--duration", "0.05"], "tracking", "pdf"),
        (["identify", "fit", "DATA", "--grid", "32"], "estimate", "svg"),
        (
            ["identify", "study", "--n-min", "50", "--n-max", "100", "--n-steps", "2"],
            "study",
            "pdf",
        ),
        (["identify", "hammerstein", "DATA", "--lags", "20"], "hammerstein", "svg"),
        (["identify", "hammerstein", "--duration", "3"], "identify_joint", "pdf"),
    ],
    ids=lambda v: " ".join(v) if isinstance(v, list) else v,
)
def test_every_figure_command_writes_the_format_asked(tmp_path, capsys, argv, figure, fmt):
    import json

    from flexarm.cli import main

    out = tmp_path / "out"
    argv = [_data(tmp_path / "d.csv") if a == "DATA" else a for a in argv]
    status = main([*argv, "--out", str(out), "--format", fmt, "--dpi", "72", "--json"])
    captured = capsys.readouterr()
    assert status == 0, captured.err
    files = json.loads(captured.out)["files"]  # the files actually written, and only they
    assert sorted(files) == sorted(p.name for p in out.iterdir())
    assert f"{figure}.{fmt}" in files and not any(f.endswith(".png") for f in files)
    assert (out / f"{figure}.{fmt}").read_bytes().startswith(MAGIC[fmt])
