"""Kernel regression estimators (paper §5, eq. 14) against independent NumPy references."""

from __future__ import annotations

import inspect

import numpy as np
import pytest

from flexarm.ident import (
    KERNELS,
    NadarayaWatson,
    NotFittedError,
    RecursiveKernelRegression,
    SemiRecursiveKernelRegression,
    evaluate_kernel,
)
from flexarm.ident.regression.kernels import kernel_code, kernel_weight
from helpers.ident import PROFILES, eq14, sums14
from helpers.ident import regression_data as data

# ----------------------------------------------------------------------------- kernels


@pytest.mark.parametrize("name", KERNELS)
def test_kernels_match_reference_and_compiled(name):
    u = np.random.default_rng(1).uniform(-1.6, 1.6, (200, 2))
    u[0] = [1.0, -1.0]  # the edge of the compact support belongs to it
    ref = np.prod(PROFILES[name](u), axis=1)
    np.testing.assert_allclose(evaluate_kernel(name, u), ref, rtol=1e-15, atol=0)
    code = kernel_code(name)
    ones, zeros = np.ones(2), np.zeros(2)
    compiled = [kernel_weight(code, row, zeros, ones, 1.0) for row in u]
    np.testing.assert_allclose(compiled, ref, rtol=1e-15, atol=0)
    if name != "gaussian":
        assert ref[0] == evaluate_kernel(name, [[1.0, -1.0]])[0]
        assert evaluate_kernel(name, [[1.0 + 1e-12]])[0] == 0.0


# ----------------------------------------------------------------------------- eq. 14


@pytest.mark.parametrize("name", KERNELS)
@pytest.mark.parametrize(
    "cls", [SemiRecursiveKernelRegression, RecursiveKernelRegression], ids=["semi", "recursive"]
)
def test_grid_mode_equals_direct_eq14(name, cls):
    X, y = data(400)
    grid = np.linspace(-0.3, 1.3, 67)[::-1]  # unsorted on purpose, partly outside the data
    est = cls(kernel=name, bandwidth=0.3, decay=0.25, grid=grid).fit(X, y)
    ref = eq14(grid, X, y, 0.3, 0.25, name, recursive=cls is RecursiveKernelRegression)
    got = est.predict(grid)
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-13, equal_nan=True)
    assert np.array_equal(np.isnan(got), np.isnan(ref))


@pytest.mark.parametrize("name", KERNELS)
def test_exact_mode_equals_grid_mode_bitwise(name):
    for d in (1, 2):
        X, y = data(300, d, seed=d)
        grid = np.random.default_rng(5).uniform(-0.2, 1.2, (40, d))
        kw = {"kernel": name, "bandwidth": [0.3, 0.5][:d], "decay": 0.2}
        exact = SemiRecursiveKernelRegression(**kw).fit(X, y).predict(grid)
        on_grid = SemiRecursiveKernelRegression(**kw, grid=grid).fit(X, y).predict(grid)
        np.testing.assert_array_equal(exact, on_grid)
        np.testing.assert_allclose(
            exact, eq14(grid, X, y, kw["bandwidth"], 0.2, name), rtol=1e-11, equal_nan=True
        )


def test_gaussian_tail_cut_is_exact():
    """Grid mode skips Gaussian weights beyond |u| = 38.61 (exactly 0.0 in float64)."""
    X, y = data(6, seed=12)
    grid = np.linspace(-1.0, 2.0, 3001)
    kw = {"bandwidth": 0.01, "decay": 0.0, "series": False}  # bit for bit: direct sums
    exact = SemiRecursiveKernelRegression(**kw).fit(X, y).predict(grid)
    on_grid = SemiRecursiveKernelRegression(**kw, grid=grid).fit(X, y).predict(grid)
    np.testing.assert_array_equal(exact, on_grid)
    ref = eq14(grid, X, y, 0.01, 0.0, "gaussian")
    np.testing.assert_allclose(on_grid, ref, rtol=1e-11, equal_nan=True)
    assert np.isnan(ref).any() and np.isfinite(ref).any()


def test_decay_zero_is_nadaraya_watson():
    X, y = data(500, seed=3)
    x = np.linspace(0, 1, 31)
    u = (x[:, None] - X[None, :]) / 0.15
    K = np.exp(-(u**2) / 2)
    hand = (K @ y) / K.sum(axis=1)
    semi = SemiRecursiveKernelRegression(bandwidth=0.15, decay=0).fit(X, y).predict(x)
    nw = NadarayaWatson(bandwidth=0.15).fit(X, y).predict(x)
    rec = RecursiveKernelRegression(bandwidth=0.15, decay=0).fit(X, y).predict(x)
    np.testing.assert_allclose(semi, hand, rtol=1e-12)
    np.testing.assert_array_equal(nw, semi)
    np.testing.assert_allclose(rec, hand, rtol=1e-12)


def test_recursive_differs_from_semi_recursive():
    X, y = data(300)
    x = np.linspace(0.1, 0.9, 9)
    semi = SemiRecursiveKernelRegression(bandwidth=0.3).fit(X, y).predict(x)
    rec = RecursiveKernelRegression(bandwidth=0.3).fit(X, y).predict(x)
    assert np.max(np.abs(semi - rec)) > 1e-6


@pytest.mark.parametrize("grid", [None, np.linspace(0, 1, 33)], ids=["exact", "grid"])
@pytest.mark.parametrize(
    "cls", [SemiRecursiveKernelRegression, RecursiveKernelRegression], ids=["semi", "recursive"]
)
def test_partial_fit_in_chunks_equals_fit(grid, cls):
    X, y = data(1000, seed=7)
    whole = cls(kernel="epanechnikov", bandwidth=0.4, grid=grid).fit(X, y)
    parts = cls(kernel="epanechnikov", bandwidth=0.4, grid=grid)
    for a, b in [(0, 1), (1, 8), (8, 9), (9, 500), (500, 1000)]:
        assert parts.partial_fit(X[a:b], y[a:b]) is parts
    assert parts.n_samples_ == whole.n_samples_ == 1000
    x = np.linspace(0, 1, 33)
    np.testing.assert_array_equal(parts.predict(x), whole.predict(x))
    if grid is None:
        np.testing.assert_array_equal(parts.bandwidths_, whole.bandwidths_)
        np.testing.assert_allclose(
            parts.bandwidths_[[0, 999], 0], 0.4 * np.array([1, 1000]) ** -0.2
        )


def test_partial_fit_in_chunks_equals_fit_2d_and_callable():
    X, y = data(600, 2, seed=8)
    grid = np.random.default_rng(9).uniform(0, 1, (20, 2))

    def tri(u):
        return np.prod(np.clip(1 - np.abs(u), 0, None), axis=1)

    for kernel in ("uniform", tri):
        for g in (None, grid):
            kw = {"kernel": kernel, "bandwidth": [0.5, 0.3], "decay": 0.3, "grid": g}
            whole = SemiRecursiveKernelRegression(**kw).fit(X, y).predict(grid)
            parts = SemiRecursiveKernelRegression(**kw)
            for a, b in [(0, 3), (3, 250), (250, 600)]:
                parts.partial_fit(X[a:b], y[a:b])
            np.testing.assert_array_equal(parts.predict(grid), whole)


def test_in_place_change_of_a_parameter_is_detected():
    grid = np.linspace(0, 1, 5)
    est = SemiRecursiveKernelRegression(grid=grid).partial_fit(X1, Y1)
    grid[0] = -1.0
    with pytest.raises(ValueError, match=r"'grid'.*changed"):
        est.partial_fit(X1, Y1)


@pytest.mark.parametrize("grid", [None, np.linspace(0, 1, 33)], ids=["exact", "grid"])
@pytest.mark.parametrize(
    ("cls", "kw"),
    [
        (SemiRecursiveKernelRegression, {"kernel": "triangular", "bandwidth": 0.4, "decay": 0.3}),
        (RecursiveKernelRegression, {"kernel": "gaussian", "bandwidth": 0.2}),
        (NadarayaWatson, {"kernel": "uniform", "bandwidth": 0.1}),
    ],
    ids=["semi", "recursive", "nw"],
)
def test_save_load_resumes_bit_for_bit(tmp_path, grid, cls, kw):
    X, y = data(900, seed=13)
    never_stopped = cls(**kw, grid=grid).fit(X, y)
    first = cls(**kw, grid=grid).partial_fit(X[:400], y[:400])
    path = tmp_path / "state.bin"
    first.save(path)
    resumed = cls.load(path)
    assert type(resumed) is cls and resumed.n_samples_ == 400
    assert repr(resumed).startswith(cls.__name__)
    resumed.partial_fit(X[400:], y[400:])
    x = np.linspace(0, 1, 33)
    np.testing.assert_array_equal(resumed.predict(x), never_stopped.predict(x))
    assert path.exists()  # written as given, no suffix added


def test_save_load_errors(tmp_path):
    with pytest.raises(NotFittedError):
        SemiRecursiveKernelRegression().save(tmp_path / "a.npz")
    est = SemiRecursiveKernelRegression(kernel=lambda u: np.exp(-np.sum(u**2, axis=1)))
    with pytest.raises(TypeError, match=r"'kernel'.*kernel name"):
        est.fit(X1, Y1).save(tmp_path / "b.npz")
    NadarayaWatson().fit(X1, Y1).save(tmp_path / "c.npz")
    with pytest.raises(ValueError, match=r"'path'.*NadarayaWatson instead"):
        SemiRecursiveKernelRegression.load(tmp_path / "c.npz")


def test_fit_restarts_but_partial_fit_continues():
    X, y = data(200)
    est = SemiRecursiveKernelRegression().fit(X, y).fit(X, y)
    assert est.n_samples_ == 200
    est.partial_fit(X, y)
    assert est.n_samples_ == 400
    np.testing.assert_allclose(est.bandwidths_[-1], 1.0 * 400**-0.2)


def test_callable_kernel_equals_named_kernel():
    X, y = data(300, 2)
    grid = np.random.default_rng(2).uniform(0, 1, (25, 2))

    def gauss(u):
        return np.exp(-0.5 * np.sum(u**2, axis=1))

    for g in (None, grid):
        named = SemiRecursiveKernelRegression(bandwidth=0.3, grid=g).fit(X, y).predict(grid)
        user = SemiRecursiveKernelRegression(gauss, bandwidth=0.3, grid=g).fit(X, y)
        np.testing.assert_allclose(user.predict(grid), named, rtol=1e-12)


# ----------------------------------------------------------------------------- behaviour


def test_consistency_rate_on_smooth_function():
    """m(x) = sin(2 pi x): twice differentiable, so with h_i ∝ i^(-1/5) Theorem 1 gives
    |m_n - m| = O(n^(-2/5)). Fitting log RMSE against log n over 1e3, 1e4, 1e5 must give a
    slope near -2/5; accepted: within ±0.15 of it."""
    grid = np.linspace(0.2, 0.8, 61)
    errs = []
    for n in (10**3, 10**4, 10**5):
        rng = np.random.default_rng(11)
        X = rng.uniform(0, 1, n)
        y = np.sin(2 * np.pi * X) + 0.1 * rng.standard_normal(n)
        est = SemiRecursiveKernelRegression("epanechnikov", bandwidth=0.5, decay=0.2, grid=grid)
        m = est.fit(X, y).predict(grid)
        errs.append(np.sqrt(np.mean((m - np.sin(2 * np.pi * grid)) ** 2)))
    assert errs[0] > errs[1] > errs[2]
    slope = np.polyfit(np.log([1e3, 1e4, 1e5]), np.log(errs), 1)[0]
    assert -0.4 - 0.15 < slope < -0.4 + 0.15, (errs, slope)


@pytest.mark.parametrize("grid", [None, np.array([0.5, 3.0, -2.0])], ids=["exact", "grid"])
def test_nan_where_no_sample_has_weight(grid):
    X, y = data(200)
    est = SemiRecursiveKernelRegression("epanechnikov", bandwidth=0.2, grid=grid).fit(X, y)
    got = est.predict([0.5, 3.0, -2.0])
    assert np.isfinite(got[0])
    assert np.isnan(got[1]) and np.isnan(got[2])


def test_two_dimensional_function():
    rng = np.random.default_rng(4)
    n = 20000
    X = rng.uniform(-1, 1, (n, 2))
    y = np.sin(X[:, 0]) + X[:, 1] ** 2 + 0.1 * rng.standard_normal(n)
    x = rng.uniform(-0.6, 0.6, (50, 2))
    est = SemiRecursiveKernelRegression(bandwidth=[0.5, 0.4], decay=0.2).fit(X, y)
    assert est.n_features_in_ == 2
    assert np.max(np.abs(est.predict(x) - (np.sin(x[:, 0]) + x[:, 1] ** 2))) < 0.05


# ----------------------------------------------------------------------------- contract


def test_get_set_params_and_repr():
    est = SemiRecursiveKernelRegression(kernel="uniform", bandwidth=0.5)
    assert est.get_params() == {
        "kernel": "uniform",
        "bandwidth": 0.5,
        "decay": 0.2,
        "grid": None,
        "binned": None,
        "series": "auto",
    }
    assert repr(est) == "SemiRecursiveKernelRegression(bandwidth=0.5, kernel='uniform')"
    assert est.set_params(decay=0.1) is est and est.decay == 0.1
    assert repr(NadarayaWatson()) == "NadarayaWatson()"
    assert "decay" not in NadarayaWatson().get_params()
    copy = type(est)(**est.get_params())
    assert copy.get_params() == est.get_params()
    assert len(repr(SemiRecursiveKernelRegression(grid=np.linspace(0, 1, 1000)))) < 150
    with pytest.raises(ValueError, match="Invalid parameter 'width'"):
        est.set_params(width=1.0)


def test_init_stores_without_validating():
    est = SemiRecursiveKernelRegression(kernel="nope", bandwidth=-1.0, decay=9.0)
    assert est.bandwidth == -1.0  # validation happens in fit


def test_sklearn_clone_if_installed():
    base = pytest.importorskip("sklearn.base")
    est = SemiRecursiveKernelRegression(bandwidth=0.5).fit(*data(50))
    copy = base.clone(est)
    assert copy.get_params() == est.get_params()
    assert not hasattr(copy, "n_samples_")


def test_not_fitted_error():
    est = SemiRecursiveKernelRegression()
    with pytest.raises(NotFittedError, match="not fitted"):
        est.predict([0.5])
    assert issubclass(NotFittedError, ValueError) and issubclass(NotFittedError, AttributeError)
    assert not hasattr(est, "X_")
    assert not hasattr(est, "n_samples_")


def test_fitted_attributes():
    X, y = data(100)
    est = SemiRecursiveKernelRegression(bandwidth=0.5).fit(X, y)
    assert est.X_.shape == (100, 1) and est.y_.shape == (100,) and est.bandwidths_.shape == (100, 1)
    np.testing.assert_array_equal(est.bandwidth_, [0.5])
    grid = np.linspace(0, 1, 5)
    g = SemiRecursiveKernelRegression(bandwidth=0.5, grid=grid).fit(X, y)
    assert g.numerator_.shape == g.denominator_.shape == (5,)
    assert not hasattr(g, "X_")
    np.testing.assert_allclose(g.predict(grid), g.numerator_ / g.denominator_)


EXACT_BANDWIDTH = (
    "The 'bandwidth' parameter of SemiRecursiveKernelRegression must be > 0. Got -1.0 instead."
)


def test_bandwidth_message_format():
    with pytest.raises(ValueError) as info:
        SemiRecursiveKernelRegression(bandwidth=-1.0).fit(*data(10))
    assert str(info.value) == EXACT_BANDWIDTH


X1, Y1 = data(20)
X2, Y2 = data(20, 2)


@pytest.mark.parametrize(
    ("params", "X", "y", "exc", "match"),
    [
        ({"bandwidth": 0.0}, X1, Y1, ValueError, "'bandwidth'.*> 0"),
        ({"bandwidth": float("nan")}, X1, Y1, ValueError, "'bandwidth'.*finite"),
        ({"bandwidth": None}, X1, Y1, TypeError, "'bandwidth'"),
        # a string is a rule name: an unknown one is a wrong value, naming the rules
        ({"bandwidth": "wide"}, X1, Y1, ValueError, "'bandwidth'.*rule.*silverman"),
        ({"bandwidth": [0.5, -0.5]}, X2, Y2, ValueError, "'bandwidth'.*> 0"),
        ({"bandwidth": [0.5, 0.5, 0.5]}, X2, Y2, ValueError, "'bandwidth'.*shape \\(2,\\)"),
        ({"kernel": "cosine"}, X1, Y1, ValueError, "'kernel'"),
        ({"kernel": 3}, X1, Y1, TypeError, "'kernel'"),
        ({"kernel": lambda u: u}, X1, Y1, ValueError, "'kernel'.*return shape"),
        ({"decay": -0.1}, X1, Y1, ValueError, "'decay'.*>= 0"),
        ({"decay": 1.5}, X1, Y1, ValueError, "'decay'.*<= 1/d"),
        ({"decay": 0.6}, X2, Y2, ValueError, "'decay'.*<= 1/d = 0.5 for d = 2"),
        ({"decay": None}, X1, Y1, TypeError, "'decay'"),
        ({}, X1, Y1[:-1], ValueError, "'y'.*length 20"),
        ({}, np.where(X1 > 0.5, np.nan, X1), Y1, ValueError, "'X'.*finite"),
        ({}, X1, np.where(Y1 > 0.5, np.inf, Y1), ValueError, "'y'.*finite"),
        ({}, X1.reshape(2, 2, 5), Y1, ValueError, "'X'.*shape"),
        ({}, X1[:0], Y1[:0], ValueError, "'X'.*at least one"),
        ({}, X1, Y1[:, None], ValueError, "'y'.*shape \\(n,\\)"),
        ({"grid": np.zeros((3, 2))}, X1, Y1, ValueError, "'grid'.*column"),
        ({"grid": [0.1, np.nan]}, X1, Y1, ValueError, "'grid'.*finite"),
    ],
)
def test_bad_input(params, X, y, exc, match):
    with pytest.raises(exc, match=match):
        SemiRecursiveKernelRegression(**params).fit(X, y)
    with pytest.raises(exc, match=match):
        SemiRecursiveKernelRegression(**params).partial_fit(X, y)


@pytest.mark.parametrize(("decay", "X", "y"), [(0.5, X2, Y2), (1.0, X1, Y1)], ids=["d2", "d1"])
def test_decay_at_the_bound_is_allowed(decay, X, y):
    """``decay = 1/d`` is accepted, and the estimate is eq. 14 with that decay."""
    est = SemiRecursiveKernelRegression(decay=decay, bandwidth=0.5).fit(X, y)
    q = np.asarray(X)[::3]
    np.testing.assert_allclose(est.predict(q), eq14(q, X, y, 0.5, decay, "gaussian"), rtol=1e-11)
    h = 0.5 * np.arange(1, len(y) + 1) ** -decay
    np.testing.assert_allclose(
        est.bandwidths_, np.repeat(h[:, None], est.n_features_in_, 1), rtol=1e-14
    )


def test_bad_input_after_fit():
    est = SemiRecursiveKernelRegression().fit(X2, Y2)
    with pytest.raises(ValueError, match=r"'X'.*2 column"):
        est.predict(X1)
    with pytest.raises(ValueError, match=r"'X'.*2 column"):
        est.partial_fit(X1, Y1)
    est.set_params(bandwidth=2.0)
    with pytest.raises(ValueError, match=r"'bandwidth'.*changed"):
        est.partial_fit(X2, Y2)
    g = SemiRecursiveKernelRegression(grid=[0.0, 0.5]).fit(X1, Y1)
    with pytest.raises(ValueError, match=r"'X'.*grid.*1 point"):
        g.predict([0.0, 0.25])
    with pytest.raises(ValueError, match=r"'kernel'.*finite"):
        SemiRecursiveKernelRegression(kernel=lambda u: np.full(len(u), np.nan)).fit(X1, Y1)


# ----------------------------------------------------------------------- decay = 0 vs statsmodels


def test_decay_zero_equals_statsmodels_kernelreg():
    kr = pytest.importorskip(
        "statsmodels.nonparametric.kernel_regression",
        reason="statsmodels is the oracle here (pip install -e '.[test]')",
    )
    X, y = data(400, seed=21)
    x = np.linspace(-0.1, 1.1, 57)
    kw = {"var_type": "c", "reg_type": "lc", "bw": [0.08]}
    if "rng" in inspect.signature(kr.KernelReg).parameters:  # silences a FutureWarning
        kw["rng"] = np.random.default_rng(0)  # (used only by bandwidth search, not here)
    ref = np.asarray(kr.KernelReg(y, X, **kw).fit(x)[0])
    assert kr.KernelReg(y, X, **kw).ckertype == "gaussian"
    nw = NadarayaWatson(bandwidth=0.08, series=False).fit(X, y).predict(x)
    semi = SemiRecursiveKernelRegression(bandwidth=0.08, decay=0.0, grid=x, series=False)
    semi = semi.fit(X, y).predict(x)
    np.testing.assert_allclose(nw, ref, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(semi, ref, rtol=1e-12, atol=1e-13)
    fast = NadarayaWatson(bandwidth=0.08, series=True).fit(X, y).predict(x)
    np.testing.assert_allclose(fast, ref, rtol=1e-12, atol=1e-13)


# ----------------------------------------------------------------------------- binned mode


BINNED_CLASSES = {
    "semi": (SemiRecursiveKernelRegression, {"decay": 0.2}, 0.2, False),
    "recursive": (RecursiveKernelRegression, {"decay": 0.25}, 0.25, True),
    "nw": (NadarayaWatson, {}, 0.0, False),
}


@pytest.mark.parametrize("which", sorted(BINNED_CLASSES))
@pytest.mark.parametrize("kernel", ["gaussian", "epanechnikov", "triangular"])
@pytest.mark.parametrize("r", [0.3, 0.1])
def test_binned_error_within_stated_bound(which, kernel, r):
    cls, kw, decay, recursive = BINNED_CLASSES[which]
    X, y = data(20000, seed=31)
    y = y + 1.5  # a mean far from 0: A and S both matter
    x = np.linspace(-0.2, 1.2, 97)
    est = cls(kernel, 0.3, grid=x, binned=r, **kw).fit(X, y)
    N, D = sums14(x, X, y, 0.3, decay, kernel, recursive)
    eN, eD = est.sum_error_bounds(x)
    # the oracle's own rounding (NumPy sums of n terms): n eps times the sum of |terms|
    _, D_abs = sums14(x, X, y, 0.3, decay, kernel, recursive)
    N_abs = sums14(x, X, np.abs(y), 0.3, decay, kernel, recursive)[0]
    oracle = len(X) * 2.0**-52
    dN = np.abs(est.numerator_ - N)
    dD = np.abs(est.denominator_ - D)
    assert np.all(dN <= eN + oracle * N_abs) and np.all(dD <= eD + oracle * D_abs)
    assert dD.max() > 1e-6 * D.max()  # the binning did happen (not all blocks exact)
    with np.errstate(invalid="ignore", divide="ignore"):
        m = N / D
    bound = est.error_bound(x)
    ok = np.isfinite(m) & np.isfinite(bound)
    assert ok.sum() > 60
    assert np.all(np.abs(est.predict(x)[ok] - m[ok]) <= bound[ok])
    # the stated per-weight bound, recomputed from the formulas of flexarm.ident.regression.binning
    m1 = {"gaussian": 2 / np.e, "epanechnikov": 1.5, "triangular": 1.0}[kernel]
    interp = {"gaussian": r**2 / 8, "epanechnikov": 3 * r**2 / 16 + 3 * r / 8}.get(kernel, r / 2)
    tau = np.exp(-81 / (2 * (1 + r**2))) + 1e-12 if kernel == "gaussian" else 0.0
    expected = (m1 * (np.sqrt(1 + r**2) - 1) if decay > 0 else 0.0) + interp + tau
    assert est.bin_error_ == pytest.approx(expected, rel=1e-12)


def test_binned_error_falls_with_the_bin_width():
    X, y = data(5000, seed=32)
    x = np.linspace(0, 1, 64)
    N, D = sums14(x, X, y, 0.1, 0.0, "gaussian")
    errors, bounds = [], []
    for r in (0.4, 0.2, 0.1, 0.05):
        est = NadarayaWatson("gaussian", 0.1, grid=x, binned=r).fit(X, y)
        errors.append(np.max(np.abs(est.predict(x) - N / D)))
        bounds.append(np.max(est.error_bound(x)))
    errors_a, bounds_a = np.array(errors), np.array(bounds)
    assert np.all(errors_a <= bounds_a)
    # second order in r for the Gaussian: halving r divides the error by about 4
    assert np.all(errors_a[1:] < errors_a[:-1] / 2.5), errors_a
    assert np.all(bounds_a[1:] < bounds_a[:-1] / 3.5), bounds_a


def streamed_saved_resumed(cls, kw, X, y, cut, step, tmp_path):
    """One fit; chunks of ``step`` up to ``cut``, saved, then the rest; and the same
    loaded from the file, then the rest. Returns ``(whole, parts, resumed)``."""
    whole = cls(**kw).fit(X, y)
    parts = cls(**kw)
    for s in range(0, cut, step):
        parts.partial_fit(X[s : min(s + step, cut)], y[s : min(s + step, cut)])
    parts.save(tmp_path / "est.npz")
    resumed = cls.load(tmp_path / "est.npz")
    for est in (parts, resumed):
        est.partial_fit(X[cut:], y[cut:])
    return whole, parts, resumed


@pytest.mark.parametrize("cls", [SemiRecursiveKernelRegression, RecursiveKernelRegression])
def test_binned_partial_fit_and_save_load_are_exact(tmp_path, cls):
    X, y = data(6000, seed=33)
    x = np.linspace(0, 1, 50)
    kw = {"kernel": "gaussian", "bandwidth": 0.2, "decay": 0.2, "grid": x, "binned": 0.2}
    whole, parts, resumed = streamed_saved_resumed(cls, kw, X, y, 4000, 777, tmp_path)
    assert resumed.binned == 0.2
    for est in (parts, resumed):
        np.testing.assert_array_equal(est.predict(x), whole.predict(x))
        np.testing.assert_array_equal(est.error_bound(x), whole.error_bound(x))
    assert not np.array_equal(whole.predict(x), cls(**{**kw, "binned": None}).fit(X, y).predict(x))


@pytest.mark.parametrize(
    ("params", "X", "exc", "match"),
    [
        ({"binned": 0.1}, X1, ValueError, r"'binned'.*None in exact mode"),
        ({"binned": 0.1, "grid": [0.0, 1.0], "kernel": "uniform"}, X1, ValueError, "binnable"),
        ({"binned": 0.1, "grid": np.zeros((2, 2))}, X2, ValueError, r"'binned'.*d = 2"),
        ({"binned": 0.9, "grid": [0.0, 1.0]}, X1, ValueError, r"'binned'.*\[0.0001, 0.5\]"),
        ({"binned": -0.1, "grid": [0.0, 1.0]}, X1, ValueError, r"'binned'.*> 0"),
        ({"binned": "fine", "grid": [0.0, 1.0]}, X1, TypeError, r"'binned'.*real"),
    ],
)
def test_binned_bad_input(params, X, exc, match):
    y = Y1 if X is X1 else Y2
    with pytest.raises(exc, match=match):
        SemiRecursiveKernelRegression(**params).fit(X, y)


def test_binned_attributes_need_binned_mode():
    est = SemiRecursiveKernelRegression(grid=[0.0, 0.5]).fit(X1, Y1)
    with pytest.raises(AttributeError, match="binned mode only"):
        _ = est.bin_error_
    with pytest.raises(AttributeError, match="binned mode only"):
        est.error_bound([0.0])


# ----------------------------------------------------------------------------- series mode


def stable_eq14(x, X, y, h, scale=1.0):
    """Eq. 14 for the Gaussian with one ``h``, each row's weights rescaled by its largest
    (exact in exact arithmetic, and free of underflow far from the data)."""
    L = -0.5 * ((x[:, None] - X[None, :]) / h) ** 2
    W = np.exp(L - L.max(axis=1, keepdims=True))
    out = (W @ y) / W.sum(axis=1)
    out[L.max(axis=1) < -0.5 * 38.6**2] = np.nan  # no sample within 38.6 h: NaN
    return out


@pytest.mark.parametrize("grid_mode", [False, True], ids=["exact", "grid"])
@pytest.mark.parametrize("h", [0.004, 0.05, 0.7])
def test_series_agrees_with_direct_summation(grid_mode, h):
    X, y = data(3000, seed=41)
    x = np.linspace(-0.3, 1.3, 201)
    kw = {"grid": x} if grid_mode else {}
    got = NadarayaWatson("gaussian", h, series=True, **kw).fit(X, y).predict(x)
    direct = NadarayaWatson("gaussian", h, series=False).fit(X, y).predict(x)
    ref = stable_eq14(x, X, y, h)
    ok = np.isfinite(ref)
    np.testing.assert_allclose(got[ok], ref[ok], rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(got[ok], direct[ok], rtol=1e-11, atol=1e-13)
    rec = RecursiveKernelRegression("gaussian", h, decay=0.0, series=True, **kw)
    np.testing.assert_allclose(rec.fit(X, y).predict(x)[ok], ref[ok], rtol=1e-11, atol=1e-13)


def test_series_far_from_the_data_stays_accurate():
    """Up to ~37.6 h the direct weights are normal floats; the series must match there."""
    X, y = data(300, seed=42)
    h = 0.01
    x = np.linspace(-0.5, 1.5, 2001)
    ref = stable_eq14(x, X, y, h)
    dist = np.min(np.abs(x[:, None] - X[None, :]), axis=1) / h
    near = dist < 37.5
    assert (dist[near] > 20).any()  # the test reaches far out
    for kw in ({}, {"grid": x}):
        got = NadarayaWatson("gaussian", h, series=True, **kw).fit(X, y).predict(x)
        np.testing.assert_allclose(got[near], ref[near], rtol=1e-11, atol=1e-13)
        assert np.all(np.isnan(got[dist > 38.7]))
        assert np.all(np.isfinite(got[dist < 38.6]))


def test_series_partial_fit_and_save_load_are_exact(tmp_path):
    X, y = data(5000, seed=43)
    x = np.linspace(0, 1, 40)
    kw = {"kernel": "gaussian", "bandwidth": 0.03, "grid": x, "series": True}
    whole, parts, resumed = streamed_saved_resumed(NadarayaWatson, kw, X, y, 3000, 611, tmp_path)
    assert resumed.series is True
    for est in (parts, resumed):
        np.testing.assert_array_equal(est.predict(x), whole.predict(x))
        np.testing.assert_array_equal(est.denominator_, whole.denominator_)
    N, D = sums14(x, X, y, 0.03, 0.0, "gaussian")
    np.testing.assert_allclose(whole.numerator_, N, rtol=1e-11, atol=1e-9)
    np.testing.assert_allclose(whole.denominator_, D, rtol=1e-11)


@pytest.mark.parametrize(
    ("params", "X", "exc", "match"),
    [
        ({"series": True, "kernel": "epanechnikov", "decay": 0.0}, X1, ValueError, "gaussian"),
        ({"series": True}, X1, ValueError, r"'series'.*decay = 0"),
        ({"series": True, "decay": 0.0}, X2, ValueError, r"'series'.*d = 2"),
        ({"series": True, "decay": 0.0, "grid": [0, 1], "binned": 0.1}, X1, ValueError, "one"),
        ({"series": 1, "decay": 0.0}, X1, TypeError, r"'series'.*bool"),
    ],
)
def test_series_bad_input(params, X, exc, match):
    y = Y1 if X is X1 else Y2
    with pytest.raises(exc, match=match):
        SemiRecursiveKernelRegression(**params).fit(X, y)


def test_series_falls_back_to_direct_sums_when_clusters_outnumber_samples():
    X = np.array([0.0, 0.3, 1000.0])  # 8e5 clusters of h/8 for 3 samples
    y = np.array([1.0, 2.0, 3.0])
    x = np.array([0.1, 0.2, 999.99])
    fast = NadarayaWatson("gaussian", 0.01, series=True).fit(X, y).predict(x)
    direct = NadarayaWatson("gaussian", 0.01, series=False).fit(X, y).predict(x)
    np.testing.assert_array_equal(fast, direct)
