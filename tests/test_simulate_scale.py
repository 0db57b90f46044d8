"""Long runs: recording every k-th instant, the reference block by block, and the
limits that refuse a run before anything is allocated."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

from flexarm import FlexibleArm, simulate
from flexarm._budget import MEMORY_ENV, TIME_ENV, memory_limit, time_limit
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.trajectories import Square
from flexarm.errors import InvalidValueError
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, PointSensor
from flexarm.sim import closed_loop
from flexarm.sim.closed_loop import recorded_instants
from flexarm.sim.references import BLOCK
from flexarm.sim.results import SimulationError

SERIES = ("q", "dq", "tau", "measurement", "reference", "desired", "tip")


@pytest.fixture(scope="module")
def arm():
    return FlexibleArm.paper()


def _assert_rows_equal(sub, full, kept):
    np.testing.assert_array_equal(sub.t, full.t[kept])
    for name in SERIES:
        np.testing.assert_array_equal(getattr(sub, name), getattr(full, name)[kept], err_msg=name)


# ------------------------------------------------------------------ record_every
@pytest.mark.parametrize("every", [1, 7, 10])
def test_record_every_keeps_the_same_run(arm, every):
    """The recorded rows are bit for bit those of the run recorded at every instant,
    noise included, and the last instant is always kept."""
    kw = {"duration": 0.5, "rng": 11, "sensor": PointSensor(1, 2.0, noise_std=1e-4)}
    full = simulate(arm, **kw)
    sub = simulate(arm, record_every=every, **kw)
    kept = recorded_instants(0, full.t.shape[0], full.t.shape[0] - 1, every)
    assert kept[-1] == full.t.shape[0] - 1
    assert np.all(kept[:-1] % every == 0)
    _assert_rows_equal(sub, full, kept)
    assert sub.info["record_every"] == every


def test_recorded_instants_of_a_run():
    np.testing.assert_array_equal(recorded_instants(0, 11, 10, 3), [0, 3, 6, 9, 10])
    np.testing.assert_array_equal(recorded_instants(0, 11, 10, 5), [0, 5, 10])
    np.testing.assert_array_equal(recorded_instants(4, 10, 10, 3), [6, 9])  # a middle chunk
    np.testing.assert_array_equal(recorded_instants(10, 11, 10, 3), [10])


def test_long_runs_take_their_reference_block_by_block(arm, monkeypatch):
    """A run long enough to take its reference one block at a time gives the
    numbers of the same run with its reference computed at once."""
    kw = {
        "duration": 2 * BLOCK * 2e-4 + 0.5,  # three blocks
        "rng": 5,
        "sensor": PointSensor(1, 2.0, model="paper", noise_std=1e-4),  # stable with JT-PD
        "record_every": 3,
    }
    at_once = simulate(arm, **kw)
    monkeypatch.setattr(closed_loop, "_WHOLE_REFERENCE_ROWS", BLOCK // 2)
    by_block = simulate(arm, **kw)
    for name in ("t", *SERIES):
        np.testing.assert_array_equal(getattr(by_block, name), getattr(at_once, name))


def test_a_diverged_run_keeps_the_rows_it_recorded(arm):
    """Too long a period: the partial result holds the recorded rows up to the
    divergence, and the same rows as the run recorded at every instant."""
    kw = {"dt": 1e-3, "check_sampling": False, "duration": 5.0}
    with pytest.raises(SimulationError) as full:
        simulate(arm, **kw)
    with pytest.raises(SimulationError) as sub:
        simulate(arm, record_every=4, **kw)
    full_t, sub_t = full.value.result.t, sub.value.result.t
    assert sub_t[-1] <= full_t[-1] < sub_t[-1] + 4e-3
    kept = np.arange(0, full_t.shape[0], 4)[: sub_t.shape[0]]
    np.testing.assert_array_equal(sub.value.result.q, full.value.result.q[kept])


@pytest.mark.parametrize("bad", [0, -1, 2.5, "10", None])
def test_record_every_must_be_a_positive_int(arm, bad):
    with pytest.raises((ValueError, TypeError), match="record_every"):
        simulate(arm, duration=0.01, record_every=bad)


# ------------------------------------------------------------------ limits
@pytest.mark.parametrize(
    "kw, needle",
    [
        ({"duration": 1e12}, "memory"),
        ({"dt": 1e-12, "duration": 1.0}, "memory"),
        ({"duration": 1e9, "record_every": 10**9}, "RK4 steps"),
        ({"delay": DelayModel(1e9, method="exact"), "duration": 1.0}, "delay line"),
    ],
    ids=["long", "fine", "slow", "delay"],
)
def test_absurd_runs_are_refused_before_allocating(arm, kw, needle):
    """Refused with what it would take and how to raise the limit, and quickly:
    no allocation anywhere near the run's size."""
    tracemalloc.start()
    try:
        with pytest.raises(InvalidValueError, match=needle) as err:
            simulate(arm, **kw)
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert peak < 50e6
    message = str(err.value)
    assert "FLEXARM_MAX_" in message and "would" in message and "\n" not in message


def test_the_limits_are_the_users(arm, monkeypatch):
    monkeypatch.setenv(MEMORY_ENV, "1M")
    assert memory_limit() == 2**20
    with pytest.raises(InvalidValueError, match=r"limit of 1 MB"):
        simulate(arm, duration=1.0)
    assert simulate(arm, duration=1.0, record_every=1000).t.shape[0] == 6
    monkeypatch.setenv(MEMORY_ENV, "0")  # no limit
    assert memory_limit() == float("inf")
    monkeypatch.setenv(TIME_ENV, "1.5m")
    assert time_limit() == 90.0
    monkeypatch.setenv(TIME_ENV, "1e-9")
    with pytest.raises(InvalidValueError, match=TIME_ENV):
        simulate(arm, duration=0.01)


@pytest.mark.parametrize("text", ["lots", "-1G", "1X", "nan", ""])
def test_a_bad_limit_is_named(monkeypatch, text):
    monkeypatch.setenv(MEMORY_ENV, text)
    with pytest.raises(InvalidValueError, match=MEMORY_ENV):
        memory_limit()


def test_joint_sensor_runs_with_noise_use_one_stream(arm):
    """Noise drawn block by block is the stream drawn at once: a seeded run with
    noise on the encoders equals the same seed's noise added by hand to a
    noise-free run's measurement at the first instant."""
    sensor = JointSensor(noise_std=1e-3)
    noisy = simulate(
        arm, JacobianTransposePD.from_arm(arm), Square(), sensor=sensor, duration=0.01, rng=3
    )
    clean = simulate(arm, duration=0.01)
    draw = np.random.default_rng(3).normal(size=(noisy.t.shape[0], 4))[0, :2] * 1e-3
    np.testing.assert_allclose(
        noisy.measurement[0, :2] - clean.measurement[0, :2], draw, rtol=1e-12, atol=1e-15
    )


# ------------------------------------------------------------------ writing long runs
def test_csv_written_by_chunks_is_numpys(arm, tmp_path):
    """The chunked writer gives byte for byte the file numpy.savetxt writes from the
    whole table (NaN rows of a diverged tail included)."""
    from flexarm.sim.results import SimulationResult

    result = simulate(arm, duration=0.2)
    result.q[-3:] = np.nan  # as a diverged tail is written
    SimulationResult._write_csv(result, tmp_path / "chunked.csv", rows_per_chunk=97)
    header, table = result.table()
    np.savetxt(
        tmp_path / "numpy.csv",
        table,
        fmt="%.10g",
        delimiter=",",
        header=",".join(header),
        comments="",
    )
    assert (tmp_path / "chunked.csv").read_bytes() == (tmp_path / "numpy.csv").read_bytes()


def test_plot_envelope_keeps_every_extreme():
    from flexarm.sim.results import envelope

    rng = np.random.default_rng(0)
    t = np.arange(100_003) * 1e-3
    y = rng.normal(size=t.shape)
    y[5000:5100] = np.nan
    te, ye = envelope(t, y, 1000)
    assert te.shape[0] <= 1000 and np.all(np.diff(te) > 0)
    assert np.nanmax(ye) == np.nanmax(y) and np.nanmin(ye) == np.nanmin(y)
    assert set(te[np.isfinite(ye)]) <= set(t)
    assert envelope(t[:999], y[:999], 1000)[1] is y[:999] or np.array_equal(
        envelope(t[:999], y[:999], 1000)[1], y[:999], equal_nan=True
    )
