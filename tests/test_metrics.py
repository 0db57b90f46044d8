"""The tracking metrics: the same numbers, bit for bit, as the plain NumPy expressions
that define them, computed with fewer passes; and runs that do not record the
measurement and the reference have the same series and metrics."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.lqg import LQG
from flexarm.sensing.sensors import JointSensor, TipSensor
from flexarm.sim import metrics as m
from flexarm.sim.references import BLOCK


# the definitions, written out as plain NumPy expressions
def rms_plain(error):
    e = error[np.isfinite(error)]
    return float(np.sqrt(np.mean(e**2))) if e.size else float("nan")


def max_plain(error):
    e = error[np.isfinite(error)]
    return float(e.max()) if e.size else float("nan")


def corners_plain(t, error, corners, window):
    out = np.full(len(corners), np.nan)
    for i, tc in enumerate(corners):
        sel = (t >= tc) & (t <= tc + window) & np.isfinite(error)
        if np.any(sel):
            out[i] = error[sel].max()
    return out


def residual_plain(t, deflection, start):
    if start >= t[-1]:
        start = t[-1] - 0.1 * (t[-1] - t[0])
    sel = (t >= start) & np.isfinite(deflection)
    return float(np.sqrt(np.mean(deflection[sel] ** 2))) if np.any(sel) else float("nan")


def effort_plain(t, tau):
    ok = np.all(np.isfinite(tau), axis=1)
    if np.count_nonzero(ok) < 2:
        return float("nan")
    return float(np.trapezoid(np.einsum("ij,ij->i", tau[ok], tau[ok]), t[ok]))


def same(a, b):
    return np.array_equal(np.asarray(a), np.asarray(b), equal_nan=True)


@pytest.mark.parametrize("seed", range(40))
def test_each_metric_is_its_plain_expression_bit_for_bit(seed):
    """Random series with NaN samples, NaN tails, windows inside and outside the run."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 3000))
    t = np.cumsum(rng.uniform(1e-3, 0.1, n))
    error = rng.uniform(0.0, 1.0, n)
    tau = rng.normal(size=(n, int(rng.integers(1, 4))))
    if seed % 3 == 0:
        error[rng.integers(0, n, 3)] = np.nan
        tau[rng.integers(0, n, 2), 0] = np.nan
    if seed % 4 == 1:
        tau[-int(rng.integers(1, n + 1)) :] = np.nan
    start = float(rng.uniform(t[0] - 1.0, t[-1] + 1.0))
    corners = list(rng.uniform(t[0] - 1.0, t[-1] + 1.0, 4))
    window = float(rng.uniform(0.0, 2.0))
    assert same(m.rms_error(error), rms_plain(error))
    assert same(m.max_error(error), max_plain(error))
    got = m.corner_errors(t, error, corners, window)
    assert same(got, corners_plain(t, error, corners, window))
    assert same(m.residual_vibration(t, error, start), residual_plain(t, error, start))
    k = m.residual_start(t, start)  # the window alone gives the same number
    assert same(m.residual_vibration(t, error[k:], start), residual_plain(t, error, start))
    assert same(m.control_effort(t, tau), effort_plain(t, tau))


@pytest.mark.parametrize("n_links", [1, 2, 3])
@pytest.mark.parametrize("rows", [1, 5, m.BLOCK, 2 * m.BLOCK + 7])
def test_the_per_row_series_by_blocks_are_the_whole_arrays_bit_for_bit(n_links, rows):
    rng = np.random.default_rng(rows + n_links)
    angles = rng.uniform(-4.0, 4.0, (rows, n_links))
    lengths = rng.uniform(0.5, 5.0, n_links)
    tip, desired = rng.normal(size=(rows, 2)), rng.normal(size=(rows, 2))
    phi = np.cumsum(angles, axis=1)  # (the same sums, left to right)
    rigid = np.stack([np.cos(phi) @ lengths, np.sin(phi) @ lengths], axis=1)
    e = tip - rigid
    assert same(m.elastic_deflection(angles, lengths, tip), np.sqrt(np.einsum("ij,ij->i", e, e)))
    d = tip - desired
    assert same(m.row_distances(tip, desired), np.sqrt(np.einsum("ij,ij->i", d, d)))
    t = np.cumsum(rng.uniform(1e-3, 0.1, rows))
    tau = rng.normal(size=(rows, n_links))
    assert same(m.control_effort(t, tau), effort_plain(t, tau))


def result_metrics_plain(res):
    """SimulationResult.metrics() as the plain expressions over every row."""
    d = res.tip - res.desired
    error = np.sqrt(np.einsum("ij,ij->i", d, d))
    phi = res.q[:, : res.n_links].copy()
    for i in range(1, res.n_links):
        phi[:, i] += phi[:, i - 1]
    rigid = np.stack([np.cos(phi) @ res.link_lengths, np.sin(phi) @ res.link_lengths], axis=1)
    e = res.tip - rigid
    elastic = np.sqrt(np.einsum("ij,ij->i", e, e))
    end = float(res.info.get("motion_end_s", res.t[-1]))
    return (
        {
            "rms_error_m": rms_plain(error),
            "max_error_m": max_plain(error),
            "corner_errors_m": corners_plain(res.t, error, res.corner_times, 1.0).tolist(),
            "residual_vibration_m": residual_plain(res.t, elastic, end),
            "control_effort_N2m2s": effort_plain(res.t, res.tau),
            "max_torque_Nm": float(np.nanmax(np.abs(res.tau))),
        },
        rigid,
        elastic,
    )


@pytest.mark.parametrize(
    "kwargs",
    [
        {"duration": 20.0},  # ends at the motion's end: the last 10 % is the window
        {"duration": 24.0},  # the window from the motion's end
        {"duration": 3.0, "record_every": 7},
    ],
)
def test_result_metrics_are_the_plain_expressions_bit_for_bit(kwargs):
    res = fa.simulate(fa.FlexibleArm.paper(), **kwargs)
    want, rigid, elastic = result_metrics_plain(res)
    got = res.metrics()
    for key, value in want.items():
        assert same(got[key], value), key
    assert same(res.rigid_tip, rigid) and same(res.elastic_deflection, elastic)


SERIES = ("t", "q", "dq", "tau", "desired", "tip")


@pytest.mark.parametrize(
    ("controller", "kwargs"),
    [
        (None, {"duration": 0.5}),  # streamed reference
        (None, {"duration": 0.5, "record_every": 3}),
        (None, {"feedforward": True, "duration": 0.5}),  # the whole reference at once
        # more rows than the whole reference at once: block by block
        (None, {"feedforward": True, "duration": 4.5 * BLOCK * 2e-4}),
        (LQG(), {"sensor": TipSensor(), "duration": 0.3}),  # the design reads the reference
        (None, {"sensor": JointSensor(noise_std=1e-4), "seed": 3, "duration": 0.5}),
    ],
)
def test_a_run_without_its_signals_is_the_same_run(controller, kwargs):
    arm = fa.FlexibleArm.paper()
    full = fa.simulate(arm, controller, **kwargs)
    bare = fa.simulate(arm, controller, record_signals=False, **kwargs)
    for name in SERIES:
        assert np.array_equal(getattr(full, name), getattr(bare, name)), name
    rows = full.t.shape[0]
    assert full.measurement.shape[0] == full.reference.shape[0] == rows
    assert bare.measurement.shape == bare.reference.shape == (rows, 0)
    a, b = full.metrics(), bare.metrics()
    a.pop("wall_time_s"), b.pop("wall_time_s")
    assert all(same(a[k], b[k]) for k in a)
    assert full.info["record_signals"] is True and bare.info["record_signals"] is False
    header, _ = bare.table()  # the table has no reference columns then
    assert "x_ref" not in header and "x_ref" in full.table()[0]


def test_record_signals_must_be_a_bool():
    with pytest.raises(TypeError, match="record_signals"):
        fa.SimulationSettings(record_signals=1)
