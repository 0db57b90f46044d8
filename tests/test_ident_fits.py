"""One-call fits from data (:mod:`flexarm.ident.fits`): the library's estimators, nothing
more; plots that take ``ax``/``fig``, return them and label every axis "quantity (unit)"."""

from __future__ import annotations

import re

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest
from matplotlib.figure import Figure

from flexarm.ident import (
    HammersteinIdentifier,
    SemiRecursiveKernelRegression,
    convergence_study,
    fit_hammerstein,
    fit_regression,
    simulate_hammerstein,
)
from flexarm.ident.hammerstein.systems import Saturation

LABEL = re.compile(r"^\S.* \([^()]+\)$")  # "quantity (unit)"


@pytest.fixture(scope="module")
def xy():
    rng = np.random.default_rng(1)
    x = rng.uniform(-1, 1, 3000)
    return x, np.tanh(2 * x) + 0.05 * rng.standard_normal(3000)


@pytest.fixture(scope="module")
def uy():
    rng = np.random.default_rng(2)
    u = rng.uniform(-2, 2, 4000)
    return u, simulate_hammerstein(Saturation(1.0), [0.5], [1.0, 0.3], u, 0.05, rng=rng)


def labels(ax):
    return [ax.get_xlabel(), ax.get_ylabel()]


def test_fit_regression_is_the_estimator_on_a_grid(xy, tmp_path):
    x, y = xy
    res = fit_regression(x, y, kernel="epanechnikov", bandwidth=0.2, grid=33, binned=0.1)
    grid = np.linspace(x.min(), x.max(), 33)
    ref = SemiRecursiveKernelRegression("epanechnikov", 0.2, grid=grid, binned=0.1).fit(x, y)
    np.testing.assert_array_equal(res.grid, grid)
    np.testing.assert_array_equal(res.estimate, ref.predict(grid))
    np.testing.assert_array_equal(res.error_bound, ref.error_bound(grid))
    s = res.summary()
    assert s["bandwidth_rule"] == "given" and s["error_bound_max"] == np.max(res.error_bound)
    assert s["last_bandwidth"] == pytest.approx(0.2 * 3000**-0.2)
    paths = res.save(tmp_path / "r")
    assert [p.name for p in paths] == ["estimate.csv", "estimate.png"]
    table = np.loadtxt(paths[0], delimiter=",", skiprows=1)
    np.testing.assert_allclose(table, np.c_[grid, res.estimate], rtol=1e-11)


def test_fit_hammerstein_is_the_identifier(uy, tmp_path):
    u, y = uy
    res = fit_hammerstein(u, y, n_lags=20, known_points=((0.0, 0.0), (1.5, 1.0)))
    model = HammersteinIdentifier(n_lags=20, known_points=((0.0, 0.0), (1.5, 1.0))).fit(u, y)
    np.testing.assert_array_equal(res.phi, model.nonlinearity(res.grid))
    np.testing.assert_array_equal(res.y_hat, model.predict(u))
    assert res.fit_percent == model.fit_percent(u, y) and res.normalisation == "two-point"
    paths = res.save(tmp_path / "h")
    assert [p.name for p in paths] == [
        "nonlinearity.csv",
        "impulse_response.csv",
        "hammerstein.png",
    ]
    ir = np.loadtxt(paths[1], delimiter=",", skiprows=1)
    np.testing.assert_allclose(ir[:, 1], model.impulse_response_, rtol=1e-11)


def test_plots_take_and_return_their_handles(xy, uy):
    x, y = xy
    fig = Figure()
    ax = fig.add_subplot()
    res = fit_regression(x, y, grid=17, x_label="u", y_label="w")
    assert res.plot(ax) is ax
    assert labels(ax) == ["u (data units)", "w (data units)"]
    assert res.plot().figure is not fig  # a new figure when none is given
    u, yy = uy
    ham = fit_hammerstein(u, yy, n_lags=12)
    f = Figure()
    assert ham.plot(f) is f and len(f.axes) == 3
    for a in f.axes:
        assert all(LABEL.match(t) for t in labels(a)), labels(a)
    study = convergence_study("smooth", n=[50, 100], repetitions=2, rng=0)
    a2 = Figure().add_subplot()
    assert study.plot(ax=a2) is a2 and a2.get_xlabel() == "n (samples)"


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda: fit_regression(np.ones(10), np.arange(10.0)), "'x'.*must vary"),
        (lambda: fit_regression([0.0, 1.0], [1.0]), "'y'.*shape"),
        (lambda: fit_regression([0.0, 1.0], [1.0, 2.0], grid=1), "'grid'.*>= 2"),
        (lambda: fit_hammerstein(np.ones(500), np.arange(500.0)), "'u'.*must vary"),
        (lambda: fit_hammerstein([0.0], [0.0]), "'u'.*at least 2"),
    ],
)
def test_bad_input(call, match):
    with pytest.raises(ValueError, match=match):
        call()


def coloured(n, seed):
    """AR(1) input, coefficient 0.9, scaled to about [-2, 2]."""
    from scipy.signal import lfilter

    e = np.random.default_rng(seed).standard_normal(n + 500)
    x = lfilter([1.0], [1.0, -0.9], e)[500:]
    return 2.0 * x / np.quantile(np.abs(x), 0.99)


def banded(n):
    u = coloured(n, 3)
    y = simulate_hammerstein(Saturation(1.0, 1.5), [0.5], [1.0, 0.3], u, 0.2, rng=4)
    return u, y, fit_hammerstein(u, y, n_lags=20, bootstrap=20, rng=5, order=1, n_knots=8)


def test_bootstrap_bands_hold_the_estimate_and_the_truth(tmp_path):
    u, y, res = banded(4000)
    b = res.bands
    assert b is not None and b.n_boot == 20 and b.method == "correlated"
    assert b.block_length == 40  # max(n**(1/3), 4 x the memory: 10 x order 1)
    np.testing.assert_array_equal(b.phi, res.model.nonlinearity_)
    assert np.all(b.phi_low <= b.phi_high) and np.all(b.impulse_low <= b.impulse_high)
    # the truth (mapped by the best affine map) lies in the band over the central inputs
    x = b.grid[(b.grid > np.quantile(u, 0.05)) & (b.grid < np.quantile(u, 0.95))]
    phi_x = res.model.nonlinearity(x)
    s, t = np.linalg.lstsq(np.c_[phi_x, np.ones_like(x)], Saturation(1.0, 1.5)(x), rcond=None)[0]
    truth = (Saturation(1.0, 1.5)(x) - t) / s
    lo, hi = np.interp(x, b.grid, b.phi_low), np.interp(x, b.grid, b.phi_high)
    assert np.mean((truth >= lo) & (truth <= hi)) > 0.8
    # drawn and saved with the bands; the same rng gives the same bands
    fig = b.plot()
    assert len(fig.axes) == 2 and all(LABEL.match(t) for a in fig.axes for t in labels(a))
    names = [p.name for p in res.save(tmp_path / "h")]
    table = np.loadtxt(tmp_path / "h" / names[0], delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 2:], np.c_[b.phi_low, b.phi_high], rtol=1e-10)
    f = Figure()
    assert res.plot(f) is f and len(f.axes) == 3
    again = fit_hammerstein(u, y, n_lags=20, bootstrap=20, rng=5, order=1, n_knots=8).bands
    np.testing.assert_array_equal(again.phi_low, b.phi_low)


def test_bootstrap_bands_narrow_as_one_over_root_n():
    """Four times the samples, about half the width (sqrt(n) scaling)."""
    small, large = banded(4000)[2].bands, banded(16000)[2].bands
    ratio = np.median(small.phi_high - small.phi_low) / np.median(large.phi_high - large.phi_low)
    assert 1.3 < ratio < 3.2, ratio


def test_hammerstein_fit_summary_reports_the_path_and_the_baseline(uy):
    u, y = uy
    s = fit_hammerstein(u, y, n_lags=12).summary()
    assert s["method"] == "white" and "white" in s["reason"] and s["whiteness"]["white"]
    assert s["baseline"]["order"] >= 1 and s["bands"] is None and s["n_knots"] is None
    c = fit_hammerstein(coloured(4000, 6), y, n_lags=12).summary()
    assert c["method"] == "correlated" and c["bandwidth"] is None
    assert c["n_knots"] == c["structure"]["n_knots"] and "selection" in c["structure"]
