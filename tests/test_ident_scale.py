"""Kernel regression at scale: blocked sums, chunk partials, iterators of chunks, Dask arrays,
save/load mid-block, and the automatic Gaussian series measured against a long-double oracle.

Bit for bit: one ``fit``, ``partial_fit`` with any chunking, chunk partials combined in order,
``fit_chunks`` and ``fit`` on Dask arrays all give the same state and estimate. The series
(``series="auto"``) agrees with direct summation to 1e-12 of the weighted mean ``|y|`` where a
sample lies within 36.6 h, and *is* the direct sum farther out.
"""

from __future__ import annotations

import itertools
import tracemalloc

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from flexarm.ident import (
    KERNELS,
    NadarayaWatson,
    RecursiveKernelRegression,
    SemiRecursiveKernelRegression,
)
from flexarm.ident.regression.accumulators import (
    BLOCK,
    ExactSamples,
    GridSums,
    SeriesMoments,
    choose,
)
from flexarm.ident.regression.accumulators.blocks import segments
from helpers.ident import fed, same_state, smoothing

GRID = np.linspace(-0.1, 1.1, 23)[::-1]  # unsorted, partly outside the data


def tri(u):
    return np.prod(np.clip(1 - np.abs(u), 0, None), axis=1)


MODES = {
    "grid": lambda b: smoothing("gaussian", (0.2,), 0.2, GRID, block=b),
    "grid-callable": lambda b: smoothing(tri, (0.3,), 0.3, GRID, block=b),
    "grid-2d": lambda b: smoothing("uniform", (0.4, 0.5), 0.2, np.c_[GRID, GRID[::-1]], block=b),
    "grid-recursive": lambda b: smoothing(
        "triangular", (0.3,), 0.25, GRID, block=b, recursive=True
    ),
    "series": lambda b: smoothing("gaussian", (0.05,), 0.0, GRID, block=b, series=True),
    "exact": lambda b: smoothing("epanechnikov", (0.3,), 0.2, None, block=b),
    "binned": lambda b: smoothing("gaussian", (0.2,), 0.2, GRID, block=b, binned=0.2),
}


def data(n, d=1, seed=0):
    rng = np.random.default_rng(seed)
    X = np.ascontiguousarray(rng.uniform(0, 1, (n, d)))
    return X, np.sin(2 * np.pi * X[:, 0]) - X[:, -1] + 0.2 * rng.standard_normal(n)


def queries(s):
    return s.grid if s.grid is not None else np.random.default_rng(1).uniform(-0.1, 1.1, (19, s.d))


# ---------------------------------------------------------------- blocked sums, any chunking


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    mode=st.sampled_from(sorted(MODES)),
    block=st.sampled_from([5, 16, 64]),
    n=st.integers(1, 260),
    cuts=st.lists(st.integers(1, 259), max_size=8),
    aligned=st.lists(st.integers(1, 8), max_size=5),
)
def test_any_chunking_and_partials_in_order_equal_one_call(mode, block, n, cuts, aligned):
    s = MODES[mode](block)
    X, y = data(n, s.d, seed=n)
    whole = fed(choose(s)(s), X, y)
    parts = fed(choose(s)(s), X, y, sorted({c for c in cuts if c < n}))
    same_state(parts, whole)
    np.testing.assert_array_equal(parts.evaluate(queries(s)), whole.evaluate(queries(s)))
    # partials computed apart (chunks starting at multiples of the block), combined in order
    edges = sorted({0, n, *(min(n, k * block) for k in itertools.accumulate(aligned))})
    combined = choose(s)(s)
    for a, b in itertools.pairwise(edges):
        p = choose(s).chunk_partials(s, np.ascontiguousarray(X[a:b]), y[a:b], a)
        combined.add_partials(p)
    same_state(combined, whole)


@pytest.mark.parametrize("kernel", [*KERNELS, "callable"])
@pytest.mark.parametrize("d", [1, 2])
def test_exact_equals_grid_bitwise_across_block_boundaries(kernel, d):
    k = tri if kernel == "callable" else kernel
    X, y = data(700, d, seed=3)
    grid = GRID[:, None] if d == 1 else np.c_[GRID, GRID[::-1]]
    bw = (0.3, 0.4)[:d]
    for n in (64, 65, 700):  # a complete last block, one sample past it, many blocks
        exact = fed(ExactSamples(smoothing(k, bw, 0.2, None, block=64)), X[:n], y[:n])
        on_grid = fed(
            GridSums(smoothing(k, bw, 0.2, grid, block=64)), X[:n], y[:n], cuts=(3, 64, 200)
        )
        np.testing.assert_array_equal(exact.evaluate(grid), on_grid.evaluate(grid))


def test_blocks_change_the_order_not_the_sums():
    X, y = data(3000, seed=4)
    one = fed(GridSums(smoothing("gaussian", (0.2,), 0.2, GRID, block=3000)), X, y).sums()
    blocked = fed(GridSums(smoothing("gaussian", (0.2,), 0.2, GRID, block=7)), X, y).sums()
    for a, b in zip(one, blocked, strict=True):
        np.testing.assert_allclose(a, b, rtol=1e-13, atol=1e-13)
    assert list(segments(18, 3, 7)) == [(0, 3, True)]
    assert list(segments(14, 3, 7)) == [(0, 3, False)]
    assert list(segments(13, 9, 7)) == [(0, 1, True), (1, 8, True), (8, 9, False)]


def test_partials_out_of_order_are_refused():
    s = MODES["grid"](16)
    X, y = data(40, seed=5)
    acc = fed(choose(s)(s), X[:16], y[:16])
    with pytest.raises(ValueError, match=r"'partials'.*starting at sample 16.*32"):
        acc.add_partials(GridSums.chunk_partials(s, X[32:], y[32:], 32))
    fed(acc, X[16:20], y[16:20])
    with pytest.raises(ValueError, match=r"'partials'.*open block is empty"):
        acc.add_partials(GridSums.chunk_partials(s, X[20:], y[20:], 20))


# --------------------------------------------------------------- estimators: real block size

N_BIG = 2 * BLOCK + 4321  # three blocks, the last one open


@pytest.fixture(scope="module")
def big():
    X, y = data(N_BIG, seed=6)
    return X[:, 0], y


ESTIMATORS = {
    "grid": (SemiRecursiveKernelRegression, {"kernel": "epanechnikov", "bandwidth": 0.2}, True),
    "series": (NadarayaWatson, {"bandwidth": 0.05}, True),
    "exact": (SemiRecursiveKernelRegression, {"kernel": "triangular", "bandwidth": 0.3}, False),
    "binned": (RecursiveKernelRegression, {"bandwidth": 0.3, "binned": 0.2}, True),
}
X_Q = np.linspace(0.0, 1.0, 17)


def make(mode):
    cls, kw, gridded = ESTIMATORS[mode]
    return cls(**kw, grid=X_Q if gridded else None)


def check_same(a, b):
    np.testing.assert_array_equal(a.predict(X_Q), b.predict(X_Q))
    same_state(a.state_.accumulator, b.state_.accumulator)


@pytest.mark.parametrize("mode", sorted(ESTIMATORS))
def test_fit_chunks_and_partial_fit_equal_fit(big, mode):
    X, y = big
    whole = make(mode).fit(X, y)
    assert type(whole.state_.accumulator).mode == mode
    sizes = [1, 999, BLOCK - 1000, 2, 12345, BLOCK, 10**9]
    edges = np.minimum(np.cumsum([0, *sizes]), N_BIG)
    chunks = [(X[a:b], y[a:b]) for a, b in itertools.pairwise(edges) if b > a]
    check_same(make(mode).fit_chunks(iter(chunks)), whole)
    streamed = make(mode)
    for c in chunks:
        streamed.partial_fit(*c)
    check_same(streamed, whole)


@pytest.mark.parametrize("mode", ["grid", "series"])
def test_save_load_mid_block_resumes_bitwise(big, mode, tmp_path):
    X, y = big
    whole = make(mode).fit(X, y)
    cut = BLOCK + 777  # mid-block: the open block's partial is in the file
    first = make(mode).partial_fit(X[:cut], y[:cut])
    first.save(tmp_path / "s.npz")
    with np.load(tmp_path / "s.npz") as z:
        assert int(z["format"]) == 2 and int(z["block"]) == BLOCK and np.any(z["open_" + key(mode)])
    resumed = type(first).load(tmp_path / "s.npz")
    resumed.partial_fit(X[cut:], y[cut:])
    check_same(resumed, whole)


def key(mode):
    return "den" if mode == "grid" else "series_md"


@pytest.mark.parametrize("mode", ["grid", "series"])
def test_format_1_files_still_load(big, mode, tmp_path):
    """A file written before the blocked sums: its sums become the closed total; resuming agrees
    with the uninterrupted fit to rounding (not bit for bit)."""
    X, y = big
    cut = BLOCK + 777
    est = make(mode).partial_fit(X[:cut], y[:cut])
    state = est.to_arrays()
    old = {k: v for k, v in state.items() if not k.startswith("open_") and k != "block"}
    old["format"] = np.array(1)
    old["series"] = np.array(mode == "series")  # format 1 stored a bool
    for k in ("num", "den", "series_mn", "series_md"):
        if k in old:
            old[k] = state[k] + state["open_" + k]
    old.pop("series_band", None)
    np.savez(tmp_path / "old.npz", **old)
    resumed = type(est).load(tmp_path / "old.npz").partial_fit(X[cut:], y[cut:])
    whole = make(mode).fit(X, y)
    np.testing.assert_allclose(resumed.predict(X_Q), whole.predict(X_Q), rtol=1e-12, atol=1e-14)


def test_iterator_fit_in_bounded_memory():
    """10**6 samples (16 MB of float64) streamed in chunks of 10**4: the peak of traced
    allocations stays within a few chunks."""
    rng = np.random.default_rng(7)
    n, chunk = 10**6, 10**4

    def chunks():
        for _ in range(n // chunk):
            X = rng.uniform(0, 1, chunk)
            yield X, np.sin(2 * np.pi * X) + 0.1 * rng.standard_normal(chunk)

    est = NadarayaWatson(bandwidth=0.05, grid=np.linspace(0, 1, 64))
    est.fit_chunks(itertools.islice(chunks(), 2))  # compile outside the trace
    tracemalloc.start()
    try:
        est.fit_chunks(chunks())
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert est.n_samples_ == n and isinstance(est.state_.accumulator, SeriesMoments)
    assert peak < 2 * 2**20, peak  # << 16 MB: a few chunks (160 kB each) and the state
    grid = np.linspace(0, 1, 64)[8:-8]  # away from the edges' bias
    assert np.max(np.abs(est.predict(grid) - np.sin(2 * np.pi * grid))) < 0.1


# ------------------------------------------------------------------------------------ Dask


@pytest.fixture(scope="module")
def dask_array():
    da = pytest.importorskip("dask.array", reason="Dask is optional: pip install -e '.[dask]'")
    return da


@pytest.mark.parametrize("mode", sorted(ESTIMATORS))
def test_dask_fit_equals_in_memory_fit(big, mode, dask_array):
    import dask

    X, y = big
    whole = make(mode).fit(X, y)
    with dask.config.set(scheduler="threads"):
        Xd = dask_array.from_array(X, chunks=50_000)  # not aligned: rechunked to blocks
        est = make(mode).fit(Xd, dask_array.from_array(y, chunks=70_000))
        check_same(est, whole)
        two = make(mode).fit(Xd[:, None], y)  # 2-D X, NumPy y
        check_same(two, whole)
        part = make(mode).partial_fit(X[:1234], y[:1234])  # mid-block, then a Dask array
        part.partial_fit(Xd[1234:], dask_array.from_array(y[1234:], chunks=99_999))
        check_same(part, whole)


def test_dask_fit_2d_grid(dask_array):
    import dask

    X, y = data(BLOCK + 100, d=2, seed=8)
    grid = np.random.default_rng(9).uniform(0, 1, (12, 2))
    kw = {"kernel": "uniform", "bandwidth": [0.2, 0.3], "grid": grid}
    whole = SemiRecursiveKernelRegression(**kw).fit(X, y)
    with dask.config.set(scheduler="threads"):
        est = SemiRecursiveKernelRegression(**kw).fit(dask_array.from_array(X, chunks=(9000, 1)), y)
    np.testing.assert_array_equal(est.predict(grid), whole.predict(grid))


def test_dask_local_cluster_processes(big, dask_array):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is optional")
    X, y = big
    whole = make("series").fit(X, y)
    with (
        distributed.LocalCluster(
            n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster),
    ):
        est = make("series").fit(dask_array.from_array(X, chunks=BLOCK), y)
    check_same(est, whole)


def test_dask_bad_input(dask_array):
    import dask

    X, y = data(500, seed=10)
    Xd, yd = dask_array.from_array(X[:, 0], chunks=100), dask_array.from_array(y, chunks=100)
    est = NadarayaWatson(bandwidth=0.1, grid=X_Q)
    with pytest.raises(ValueError, match=r"'bandwidth'.*a number to fit from a Dask array"):
        NadarayaWatson(bandwidth="silverman").fit(Xd, yd)
    with pytest.raises(ValueError, match=r"'y'.*length 500"):
        est.fit(Xd, yd[:-1])
    with pytest.raises(ValueError, match=r"'X'.*shape \(n,\) or \(n, d\)"):
        est.fit(Xd.reshape(5, 10, 10), yd)
    with pytest.raises(ValueError, match=r"'y'.*shape \(n,\)"):
        est.fit(Xd, yd[:, None])
    with pytest.raises(ValueError, match=r"'X'.*known chunk sizes"):
        est.fit(Xd[Xd > 2], yd)
    with pytest.raises(TypeError, match=r"'X'.*real"):
        est.fit(Xd.astype(complex), yd)
    bad = np.where(np.arange(500) == 321, np.nan, X[:, 0])
    with dask.config.set(scheduler="threads"), pytest.raises(ValueError, match=r"'X'.*finite.*"):
        est.fit(dask_array.from_array(bad, chunks=100), yd)
    assert not hasattr(est, "n_samples_")  # a failed fit leaves no state


def test_dask_exact_mode_checks_memory_first(dask_array, monkeypatch):
    monkeypatch.setenv("FLEXARM_MAX_MEMORY", "64k")
    X, y = data(5000, seed=14)
    est = SemiRecursiveKernelRegression(bandwidth=0.2)
    with pytest.raises(ValueError, match=r"exact mode.*memory.*Give a grid"):
        est.fit(dask_array.from_array(X[:, 0], chunks=1000), y)
    SemiRecursiveKernelRegression(bandwidth=0.2, grid=X_Q).fit(dask_array.from_array(X), y)


# ---------------------------------------------------------------- iterators: bad input


@pytest.mark.parametrize(
    ("chunks", "exc", "match"),
    [
        (5, TypeError, r"'chunks'.*iterable of \(X, y\) pairs.*int"),
        (np.zeros((3, 2)), TypeError, r"'chunks'.*iterable.*ndarray"),
        ([(np.zeros(3), np.zeros(3), 1)], TypeError, r"'chunks'.*pairs.*position 0"),
        ([], ValueError, r"'chunks'.*at least one"),
        ([(np.zeros(3), np.zeros(3)), (np.zeros((2, 2)), np.zeros(2))], ValueError, r"'X'.*1 col"),
        ([(np.zeros(3), np.zeros(3)), ([0, np.nan], [1, 2])], ValueError, r"'X'.*finite.*chunk 1"),
        ([(np.zeros(3), np.zeros(2))], ValueError, r"'y'.*length 3"),
    ],
)
def test_fit_chunks_bad_input(chunks, exc, match):
    est = NadarayaWatson(bandwidth=0.1, grid=X_Q)
    with pytest.raises(exc, match=match):
        est.fit_chunks(chunks)
    assert not hasattr(est, "n_samples_")


def test_fit_chunks_refuses_bandwidth_rules():
    with pytest.raises(ValueError, match=r"'bandwidth'.*from an iterator of chunks.*silverman"):
        NadarayaWatson(bandwidth="silverman").fit_chunks([(np.zeros(3), np.zeros(3))])


# ------------------------------------------------------------- the automatic Gaussian series


@pytest.mark.parametrize(
    ("cls", "kw", "series"),
    [
        (NadarayaWatson, {}, True),
        (NadarayaWatson, {"grid": np.linspace(0, 1, 64)}, True),
        (SemiRecursiveKernelRegression, {"decay": 0.0}, True),
        (RecursiveKernelRegression, {"decay": 0.0, "grid": np.linspace(0, 1, 64)}, True),
        (SemiRecursiveKernelRegression, {}, False),  # decay 0.2: h_i varies
        (NadarayaWatson, {"kernel": "epanechnikov"}, False),
        (NadarayaWatson, {"grid": np.linspace(0, 1, 64), "binned": 0.1}, False),
        (NadarayaWatson, {"grid": np.linspace(0, 1e4, 64)}, False),  # too many clusters
        (NadarayaWatson, {"grid": np.linspace(0, 100, 64)}, False),  # 0.2 points per window
        (NadarayaWatson, {"series": False}, False),
    ],
)
def test_auto_series_is_picked_where_documented(cls, kw, series):
    X, y = data(300, seed=11)
    est = cls(**{"bandwidth": 0.05, **kw}).fit(X[:, 0], y)
    assert est.series == kw.get("series", "auto")
    assert est.state_.accumulator.setup.series is series
    if "grid" in kw:
        assert isinstance(est.state_.accumulator, SeriesMoments) is series
    two_d = NadarayaWatson(bandwidth=0.05).fit(*data(50, d=2))
    assert two_d.state_.accumulator.setup.series is False


def oracle(x, X, y, h):
    """N, D and A = sum w |y| in long double (no underflow before e**-11355)."""
    u = (x.astype(np.longdouble)[:, None] - X.astype(np.longdouble)[None, :]) / np.longdouble(h)
    W = np.exp(-u * u / 2)
    return (W * y).sum(axis=1), W.sum(axis=1), (W * np.abs(y)).sum(axis=1)


def adversarial(case, rng):
    n = 4000
    if case == "wide range":
        X = rng.uniform(-300, 300, n)
        return X, rng.standard_normal(n) * 1e3, 2.0, np.linspace(-380, 380, 257)
    if case == "mixed signs, cancelling":
        X = rng.uniform(0, 1, n)
        y = np.where(np.arange(n) % 2, 1e6, -1e6) + rng.standard_normal(n)
        return X, y, 0.03, np.linspace(-0.2, 1.2, 257)
    if case == "far queries":
        X = rng.uniform(0, 1, 300)
        return X, rng.standard_normal(300), 0.01, np.linspace(-0.45, 1.45, 1401)
    if case == "large offset":
        X = 1e6 + rng.uniform(0, 1, n)
        return X, np.cos(9 * X) + rng.standard_normal(n), 0.02, 1e6 + np.linspace(-0.1, 1.1, 257)
    # duplicates and gaps: a few distinct values, a small h
    X = rng.choice([0.0, 0.001, 0.5, 0.5005, 0.9], n)
    return X, rng.standard_normal(n) - 3.0, 0.002, np.linspace(-0.05, 0.95, 257)


CASES = ["wide range", "mixed signs, cancelling", "far queries", "large offset", "duplicates"]


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("gridded", [False, True], ids=["exact", "grid"])
def test_auto_series_agrees_with_direct_summation_to_1e12(case, gridded):
    X, y, h, x = adversarial(case, np.random.default_rng(CASES.index(case)))
    kw = {"grid": x} if gridded else {}
    auto = NadarayaWatson(bandwidth=h, **kw).fit(X, y)
    assert auto.state_.accumulator.setup.series  # the series is what is measured here
    direct = NadarayaWatson(bandwidth=h, series=False, **kw).fit(X, y).predict(x)
    got = auto.predict(x)
    N, D, A = oracle(x, X, y, h)
    near = np.min(np.abs(x[:, None] - X[None, :]), axis=1) < 36.6 * h
    assert near.any()
    scale = np.asarray(A[near] / D[near], dtype=np.float64)  # weighted mean |y|
    m = np.asarray(N[near] / D[near], dtype=np.float64)
    assert np.all(np.abs(got[near] - m) <= 1e-12 * scale)
    assert np.all(np.abs(direct[near] - m) <= 1e-12 * scale)
    assert np.all(np.abs(got[near] - direct[near]) <= 1e-12 * scale)
    # beyond 36.6 h from every sample: the direct sums themselves, bit for bit
    far = np.min(np.abs(x[:, None] - X[None, :]), axis=1) > 36.7 * h
    np.testing.assert_array_equal(got[far], direct[far])
    if case == "far queries":
        assert far.sum() > 100 and np.isnan(got[far]).any() and np.isfinite(got[far]).any()


@pytest.mark.parametrize(
    ("value", "exc", "match"),
    [("fast", ValueError, r"'series'.*True, False or 'auto'"), (None, TypeError, r"'series'")],
)
def test_series_bad_values(value, exc, match):
    with pytest.raises(exc, match=match):
        NadarayaWatson(series=value).fit(*data(10))


# ------------------------------------------------------------------ threads: the same numbers


def test_split_over_threads_changes_no_bit(monkeypatch):
    from flexarm.ident.regression.accumulators import _threads

    X, y = data(3000, d=2, seed=12)
    grid2 = np.random.default_rng(13).uniform(0, 1, (40, 2))
    cases = [
        (SemiRecursiveKernelRegression, {"bandwidth": 0.3}, X[:, 0], GRID),
        (SemiRecursiveKernelRegression, {"kernel": "uniform", "bandwidth": [0.3, 0.4]}, X, grid2),
    ]
    for cls, kw, XX, q in cases:
        for g in (None, q):
            monkeypatch.setattr(_threads, "MIN_WORK", 2**62)
            serial = cls(**kw, grid=g).fit(XX, y).predict(q)
            monkeypatch.setattr(_threads, "MIN_WORK", 1)
            assert _threads.workers(10**6, 40) == min(_threads.cores(), 40)
            np.testing.assert_array_equal(cls(**kw, grid=g).fit(XX, y).predict(q), serial)
