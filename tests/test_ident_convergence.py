"""Monte Carlo convergence study: the rate of Theorem 1, seeded reproducibility, bad input."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import numpy as np
import pytest

from flexarm.ident import ConvergenceResult, convergence_study
from flexarm.ident.regression.convergence import FUNCTIONS, regression_function
from helpers.ident import eq14, silverman

NS = (250, 500, 1000, 2000, 4000, 8000)


@pytest.fixture(scope="module")
def smooth():
    return convergence_study("smooth", n=NS, repetitions=12, rng=2026)


def test_smooth_rate_near_theory(smooth):
    """sin(pi x), p = 2, decay 1/5: MISE ~ n**-0.8. Tolerance 0.12 on the slope: with 12
    repetitions the MISE at each n has a relative std error of ~10%, which moves a
    fitted slope over a 32x range of n by about +-0.06 (twice that allowed)."""
    assert smooth.theory_slope == pytest.approx(-0.8)
    assert abs(smooth.slope - smooth.theory_slope) < 0.12, smooth.slope
    assert np.all(np.diff(smooth.mise) < 0)


def test_quantizer_converges_slower_than_smooth(smooth):
    """A jump (p = 1/2) cannot reach the smooth rate."""
    q = convergence_study("quantizer", n=NS, repetitions=6, rng=2026)
    assert q.theory_slope == pytest.approx(-0.5)
    assert q.slope > smooth.slope + 0.2
    assert q.mise[-1] < q.mise[0]


def direct_ises(h1_of):
    """The deadzone study with n = 50, 120, 2 repetitions, seed 11, 41 points, by hand:
    the same draws, eq. 14 by NumPy (Gaussian, decay 1/3), the trapezoid rule; ``h1_of(X)``
    is the repetition's ``h_1``. Returns the ISE, shape (2 repetitions, 2 sizes)."""
    rng = np.random.default_rng(11)
    x = np.linspace(-0.5, 0.5, 41)
    m = FUNCTIONS["deadzone"][0]
    ises = []
    for _ in range(2):
        X = rng.uniform(-1, 1, 120)
        y = m(X) + 0.1 * rng.standard_normal(120)
        h1 = h1_of(X)
        errors = [eq14(x, X[:n], y[:n], h1, 1 / 3, "gaussian") - m(x) for n in (50, 120)]
        ises.append([np.trapezoid(err**2, x) for err in errors])
    return np.array(ises)


def test_mise_matches_a_direct_computation():
    """Silverman's h_1 for the last sample: h_120 is the rule's (decay 1/3, p = 1)."""
    res = convergence_study("deadzone", n=[50, 120], repetitions=2, rng=11, grid=41)
    ises = direct_ises(lambda X: silverman(X, decay=1 / 3)[0])
    np.testing.assert_allclose(res.mise, ises.mean(axis=0), rtol=1e-10)
    np.testing.assert_allclose(res.std, ises.std(axis=0, ddof=1), rtol=1e-8)
    assert res.settings["decay"] == pytest.approx(1 / 3)
    assert res.settings["bandwidth"] == "silverman" and len(res.settings["h1"]) == 2


def test_fixed_bandwidth_matches_a_direct_computation():
    """A number fixes h_1 for every repetition (the study's earlier default, 0.3)."""
    res = convergence_study("deadzone", n=[50, 120], repetitions=2, rng=11, grid=41, bandwidth=0.3)
    np.testing.assert_allclose(res.mise, direct_ises(lambda X: 0.3).mean(axis=0), rtol=1e-10)
    assert res.settings["bandwidth"] == 0.3 and res.settings["h1"] == [0.3, 0.3]


def test_seeded_reproducibility():
    a = convergence_study("saturation", n=[100, 400], repetitions=3, rng=5)
    b = convergence_study("saturation", n=[100, 400], repetitions=3, rng=np.random.default_rng(5))
    c = convergence_study("saturation", n=[100, 400], repetitions=3, rng=6)
    np.testing.assert_array_equal(a.mise, b.mise)
    np.testing.assert_array_equal(a.std, b.std)
    assert not np.array_equal(a.mise, c.mise)


def test_user_callable_and_options():
    res = convergence_study(
        np.tanh,
        n=[100, 300],
        repetitions=2,
        rng=1,
        kernel="epanechnikov",
        distribution="normal",
        order=2,
        noise=0.0,
        bandwidth=0.5,
    )
    assert res.order == 2 and res.settings["function"] == "tanh"
    assert res.settings["decay"] == pytest.approx(0.2)
    with pytest.raises(ValueError, match=r"'function'.*same shape"):
        convergence_study(lambda x: 1.0, n=[10, 20], repetitions=2, rng=0)


def test_result_table_pandas_and_plot(smooth):
    assert isinstance(smooth, ConvergenceResult)
    header, table = smooth.table()
    assert header == ["n", "mise", "std"] and table.shape == (len(NS), 3)
    df = smooth.to_pandas()
    assert list(df.columns) == header and len(df) == len(NS)
    ax = smooth.plot()
    assert len(ax.lines) >= 2 and ax.get_xscale() == "log" and ax.get_yscale() == "log"
    s = smooth.summary()
    assert s["slope"] == smooth.slope and s["n"] == list(NS)


def test_progress_bar_only_on_a_tty(capsys):
    convergence_study("smooth", n=[20, 40], repetitions=2, rng=0, progress=True)
    assert capsys.readouterr().err == ""  # pytest's stderr is not a terminal


def test_regression_functions():
    np.testing.assert_allclose(regression_function("smooth")(np.array([0.5])), [1.0])
    np.testing.assert_array_equal(
        regression_function("deadzone")(np.array([0.2, -0.5])), [0.0, -0.2]
    )
    np.testing.assert_allclose(
        regression_function("saturation")(np.array([0.2, 1.0])), [0.3, 0.75], rtol=1e-15
    )


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"function": "cosine"}, ValueError, "'function'"),
        ({"function": 3}, TypeError, "'function'"),
        ({"n": [100]}, ValueError, "'n'.*at least two"),
        ({"n": [100, 50]}, ValueError, "'n'.*increasing"),
        ({"n": [10.5, 20]}, ValueError, "'n'"),
        ({"repetitions": 1}, ValueError, "'repetitions'.*>= 2"),
        ({"noise": -1.0}, ValueError, "'noise'.*>= 0"),
        ({"distribution": "cauchy"}, ValueError, "'distribution'"),
        ({"bandwidth": 0.0}, ValueError, "'bandwidth'.*> 0"),
        ({"interval": (0.5, -0.5)}, ValueError, "'interval'"),
        ({"order": -1}, ValueError, "'order'.*> 0"),
        ({"kernel": "cosine"}, ValueError, "'kernel'"),
        ({"progress": "yes"}, TypeError, "'progress'"),
    ],
)
def test_bad_input(kwargs, exc, match):
    base = {"n": [10, 20], "repetitions": 2, "rng": 0}
    with pytest.raises(exc, match=match):
        convergence_study(**{**base, **kwargs})
