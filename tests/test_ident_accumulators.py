"""The accumulators (one per mode) against each other and against eq. 14 written in NumPy;
chunks against one call; ``state()``/``from_state()`` round trips for every mode."""

from __future__ import annotations

import numpy as np
import pytest

from flexarm.ident import KERNELS, NadarayaWatson, SemiRecursiveKernelRegression
from flexarm.ident.regression.accumulators import (
    Accumulator,
    BinnedSums,
    ExactSamples,
    GridSums,
    SeriesMoments,
    choose,
)
from helpers.ident import eq14, fed, regression_data, same_state, smoothing, sums14


def data(n, d=1, seed=0):
    X, y = regression_data(n, d, seed)
    return np.ascontiguousarray(X.reshape(n, -1)), y


GRID1 = np.linspace(-0.2, 1.2, 41)[::-1]  # unsorted on purpose, partly outside the data


def test_choose_picks_one_class_per_mode():
    assert choose(smoothing()) is ExactSamples
    assert choose(smoothing(grid=GRID1)) is GridSums
    assert choose(smoothing(grid=GRID1, binned=0.1)) is BinnedSums
    assert choose(smoothing("gaussian", decay=0.0, grid=GRID1, series=True)) is SeriesMoments
    for cls in (ExactSamples, GridSums, BinnedSums, SeriesMoments):
        assert issubclass(cls, Accumulator) and cls.mode in ("exact", "grid", "binned", "series")


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("recursive", [False, True], ids=["semi", "recursive"])
@pytest.mark.parametrize("d", [1, 2])
def test_exact_equals_grid_bitwise_and_both_equal_eq14(kernel, recursive, d):
    X, y = data(300, d, seed=d)
    grid = GRID1[:, None] if d == 1 else np.random.default_rng(5).uniform(-0.2, 1.2, (30, 2))
    bw = [0.3, 0.5][:d]
    exact = fed(ExactSamples(smoothing(kernel, bw, 0.2, recursive=recursive)), X, y)
    on_grid = fed(GridSums(smoothing(kernel, bw, 0.2, grid, recursive=recursive)), X, y)
    m_exact, m_grid = exact.evaluate(grid), on_grid.evaluate(grid)
    np.testing.assert_array_equal(m_exact, m_grid)
    ref = eq14(grid, X, y, bw, 0.2, kernel, recursive=recursive)
    np.testing.assert_allclose(m_grid, ref, rtol=1e-11, atol=1e-13, equal_nan=True)
    assert np.array_equal(np.isnan(m_grid), np.isnan(ref))
    N, D = sums14(grid, X, y, bw, 0.2, kernel, recursive=recursive)
    num, den = on_grid.grid_sums()
    np.testing.assert_allclose(num, N, rtol=1e-11, atol=1e-12)
    np.testing.assert_allclose(den, D, rtol=1e-11, atol=1e-12)


@pytest.mark.parametrize("kernel", ["gaussian", "epanechnikov", "triangular"])
@pytest.mark.parametrize("r", [0.2, 0.4])
def test_binned_is_within_its_bound_of_grid_sums(kernel, r):
    X, y = data(8000, seed=3)
    y = y + 1.0
    s = smoothing(kernel, (0.2,), 0.2, grid=GRID1)
    exact = fed(GridSums(s), X, y)
    binned = fed(BinnedSums(smoothing(kernel, (0.2,), 0.2, grid=GRID1, binned=r)), X, y)
    N, D = exact.sums()
    Nb, Db = binned.sums()
    where = np.arange(len(GRID1))
    eN, eD = binned.sum_error_bounds(where)
    tiny = len(X) * 2.0**-52 * (np.abs(N) + D)  # the exact sums' own rounding
    assert np.all(np.abs(Nb - N) <= eN + tiny) and np.all(np.abs(Db - D) <= eD + tiny)
    assert np.max(np.abs(Db - D)) > 0  # binning happened


@pytest.mark.parametrize("recursive", [False, True], ids=["semi", "recursive"])
def test_series_equals_grid_sums_to_rounding(recursive):
    X, y = data(3000, seed=4)
    kw = {"kernel": "gaussian", "bw": (0.05,), "decay": 0.0, "recursive": recursive}
    exact = fed(GridSums(smoothing(**kw, grid=GRID1)), X, y)
    series = fed(SeriesMoments(smoothing(**kw, grid=GRID1, series=True)), X, y)
    ok = ~np.isnan(exact.evaluate(GRID1[:, None]))
    np.testing.assert_allclose(
        series.evaluate(GRID1[:, None])[ok], exact.evaluate(GRID1[:, None])[ok], rtol=1e-11
    )
    np.testing.assert_allclose(series.sums()[1], exact.sums()[1], rtol=1e-11, atol=1e-300)


MODES = {
    "exact": lambda: smoothing("triangular", (0.3,), 0.25),
    "exact-2d": lambda: smoothing("gaussian", (0.3, 0.4), 0.2),
    "grid": lambda: smoothing("uniform", (0.3,), 0.3, recursive=True, grid=GRID1),
    "grid-2d": lambda: smoothing("epanechnikov", (0.4, 0.5), 0.2, grid=np.c_[GRID1, GRID1[::-1]]),
    "binned": lambda: smoothing("gaussian", (0.2,), 0.2, grid=GRID1, binned=0.2),
    "series": lambda: smoothing("gaussian", (0.05,), 0.0, grid=GRID1, series=True),
}


def queries(s):
    return s.grid if s.grid is not None else np.random.default_rng(1).uniform(0, 1, (25, s.d))


@pytest.mark.parametrize("mode", sorted(MODES))
def test_chunks_equal_one_call_bitwise(mode):
    s = MODES[mode]()
    X, y = data(5000, s.d, seed=6)
    whole = fed(choose(s)(s), X, y)
    parts = fed(choose(s)(s), X, y, cuts=(1, 2, 17, 999, 1000, 3001))
    assert parts.n_samples == whole.n_samples == 5000
    np.testing.assert_array_equal(parts.evaluate(queries(s)), whole.evaluate(queries(s)))
    same_state(parts, whole)


@pytest.mark.parametrize("mode", sorted(MODES))
def test_state_round_trip_resumes_bitwise(mode):
    s = MODES[mode]()
    X, y = data(5000, s.d, seed=7)
    never_stopped = fed(choose(s)(s), X, y)
    first = fed(choose(s)(s), X[:2222], y[:2222])
    state = first.state()
    assert all(isinstance(v, np.ndarray) and v.dtype != object for v in state.values())
    resumed = type(first).from_state(s, {k: v.copy() for k, v in state.items()})
    assert resumed.n_samples == 2222 and resumed.mode == first.mode
    for k, v in state.items():
        np.testing.assert_array_equal(resumed.state()[k], v, err_msg=k)
    resumed.add_chunk(np.ascontiguousarray(X[2222:]), y[2222:])
    np.testing.assert_array_equal(resumed.evaluate(queries(s)), never_stopped.evaluate(queries(s)))
    # the state is a copy: feeding the original afterwards does not change it
    first.add_chunk(np.ascontiguousarray(X[2222:2230]), y[2222:2230])
    assert int(state["n_samples"]) == 2222


@pytest.mark.parametrize(
    ("cls", "kw"),
    [
        (SemiRecursiveKernelRegression, {"kernel": "triangular", "bandwidth": 0.3}),
        (SemiRecursiveKernelRegression, {"bandwidth": 0.3, "grid": GRID1}),
        (SemiRecursiveKernelRegression, {"bandwidth": 0.2, "grid": GRID1, "binned": 0.1}),
        (NadarayaWatson, {"bandwidth": 0.05, "grid": GRID1, "series": True}),
    ],
    ids=["exact", "grid", "binned", "series"],
)
def test_estimator_file_is_the_hyperparameters_plus_the_accumulator_state(tmp_path, cls, kw):
    X, y = data(1500, seed=8)
    est = cls(**kw).fit(X, y)
    est.save(tmp_path / "e.npz")
    with np.load(tmp_path / "e.npz", allow_pickle=False) as z:
        saved = {k: z[k] for k in z.files}
    acc_state = est.state_.accumulator.state()
    for k, v in acc_state.items():  # the accumulator's state, unchanged
        np.testing.assert_array_equal(saved[k], v, err_msg=k)
    header = set(saved) - set(acc_state)
    assert header <= {
        "format",
        "estimator",
        "kernel",
        "bandwidth",
        "decay",
        "n_features_in",
        "series",
        "grid",
        "binned",
    }


# ---------------------------------------------------- exact mode's windows: every sample's bits


@pytest.mark.parametrize("kernel", KERNELS)
@pytest.mark.parametrize("decay", [0.0, 0.5])
def test_exact_windows_equal_the_sum_over_every_sample_bitwise(kernel, decay):
    """Exact mode (d = 1) visits each sample's window of the sorted query points only; every
    point gets the bits of the plain loop over every sample (zero weights skipped)."""
    from flexarm.ident.regression.accumulators import _loops

    rng = np.random.default_rng(21)
    X = np.r_[rng.uniform(0, 1, 400), rng.normal(0.3, 1e-3, 100)][:, None]
    y = np.sin(7 * X[:, 0]) - 0.5 + 0.1 * rng.standard_normal(500)
    q = np.r_[rng.uniform(-0.5, 1.5, 60), X[:20, 0], X[:5, 0], 0.3, 0.3, 9.0][:, None]
    s = smoothing(kernel, (0.2,), decay, block=64)
    acc = fed(ExactSamples(s), X, y, cuts=(10, 64, 300))
    every = _loops.exact_predict(s.code, q, acc.X, acc.y, acc.h, acc.scale, 64)
    got = acc.evaluate(q)
    np.testing.assert_array_equal(got, every)
    assert np.isnan(got[-1]) and not np.isnan(got[60:-1]).any()  # 9.0: beyond every window
    ref = eq14(q, X, y, (0.2,), decay, kernel)
    np.testing.assert_allclose(got, ref, rtol=1e-11, atol=1e-13, equal_nan=True)
    assert acc.evaluate(np.zeros((0, 1))).shape == (0,)


def test_window_search_is_searchsorted():
    """The bucket-guided search of the windows returns ``np.searchsorted`` on any sorted
    points (even, uneven, repeated, a tiny span far from 0, a huge outlier, one point),
    from its own table's guesses and from guesses that are wrong by any amount."""
    from flexarm.ident.regression.accumulators._loops import locate, search_table

    rng = np.random.default_rng(22)
    cases = [
        np.linspace(-1, 1, 257),
        np.sort(rng.normal(0, 1, 200) ** 3),
        1e10 + np.sort(rng.integers(0, 5, 100)) * 1e-6,
        np.r_[np.zeros(50), 1e300],
        np.sort(rng.choice([-3.0, 0.0, 5e-324, 2.0], 80)),
        np.array([0.25]),
    ]
    for gs in cases:
        floats, table = search_table(gs)
        wrong = rng.integers(0, len(gs) + 1, table.shape[0])  # guesses off by any amount
        near = np.r_[gs, np.nextafter(gs, np.inf), np.nextafter(gs, -np.inf)]
        values = np.r_[near, rng.uniform(gs[0] - 1, gs[-1] + 1, 200), np.inf, -np.inf, 1e308]
        for right, side in ((False, "left"), (True, "right")):
            expected = np.searchsorted(gs, values, side=side)
            for guesses in (table, wrong):
                got = [locate(gs, v, right, floats, guesses) for v in values]
                np.testing.assert_array_equal(got, expected)


def test_series_at_many_points_equals_each_point_alone_bitwise():
    """The series is evaluated cluster by cluster over the run of sorted points in reach;
    each point must get the bits it gets alone (its clusters' terms in cluster order), in
    the compiled evaluation and in exact mode (unsorted, repeated points)."""
    from flexarm.ident.regression.kernels import gauss_series_eval, gauss_series_moments

    X, y = data(5000, seed=23)
    q = np.r_[np.random.default_rng(24).uniform(-0.3, 1.3, 40), 0.5, 0.5, 3.0]
    h, origin, clusters = 0.04, -1.7, 400
    mn, md = np.zeros((clusters, 28)), np.zeros((clusters, 28))
    gauss_series_moments(X[:, 0], y, 1.0, origin, h, mn, md)
    qs = np.sort(q)
    together = gauss_series_eval(qs, origin, h, mn, md)
    alone = [gauss_series_eval(np.array([v]), origin, h, mn, md) for v in qs]
    for k in range(3):
        np.testing.assert_array_equal(together[k], [a[k][0] for a in alone])
    assert np.all(together[1][:-1] > 0) and together[1][-1] == 0.0  # 3.0: no cluster in reach

    acc = fed(ExactSamples(smoothing("gaussian", (h,), 0.0, series=True)), X, y)
    m = acc.evaluate(q[:, None])
    np.testing.assert_array_equal(m, np.concatenate([acc.evaluate(np.array([[v]])) for v in q]))
    assert np.isfinite(m[:-1]).all() and np.isnan(m[-1])  # 3.0: 50 h away
