"""Many runs at once (flexarm.simulate_many): each result bit for bit the run done
alone, in order, with failures kept per run."""

from __future__ import annotations

import functools

import numpy as np
import pytest

import flexarm
from flexarm import FlexibleArm, Link, simulate, simulate_open_loop
from flexarm.control.controllers import JacobianTransposePD
from flexarm.control.lqg import LQG
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, PointSensor, TipSensor
from flexarm.sim.batch import iter_simulations, simulate_many
from flexarm.sim.results import SimulationError

SERIES = ("t", "q", "dq", "tau", "measurement", "reference", "desired", "tip")


def _runs():
    paper = FlexibleArm.paper()
    hubs = FlexibleArm([Link(4.5, 1676.0, 0.335, n_modes=1, hub_inertia=3.0)] * 2)
    jt = JacobianTransposePD.from_arm(paper)
    return [
        {"arm": paper, "duration": 0.3, "rng": 1, "sensor": JointSensor(noise_std=1e-4)},
        {"arm": paper, "duration": 0.3, "rng": 2, "sensor": JointSensor(noise_std=1e-4)},
        {"arm": hubs, "duration": 0.3, "dt": 5e-4, "controller": jt},
        {
            "arm": paper,
            "duration": 0.3,
            "sensor": PointSensor(1, 2.0, model="paper", noise_std=1e-4),
            "delay": DelayModel(0.002),
            "rng": 4,
        },
        {"arm": paper, "duration": 0.3, "controller": LQG(), "sensor": TipSensor(), "rng": 5},
        {"arm": paper, "duration": 0.3, "record_every": 4},
    ]


def _assert_same(a, b):
    for name in SERIES:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)
    assert {k: v for k, v in a.info.items() if k != "wall_time_s"} == {
        k: v for k, v in b.info.items() if k != "wall_time_s"
    }


@pytest.mark.parametrize("workers", [1, 2, 3])
def test_each_result_is_the_run_done_alone(workers):
    runs = _runs()
    alone = [simulate(r["arm"], **{k: v for k, v in r.items() if k != "arm"}) for r in runs]
    together = simulate_many(runs, workers=workers)
    assert len(together) == len(runs)
    for a, b in zip(together, alone, strict=True):
        _assert_same(a, b)


def test_top_level_name_and_callables():
    arm = FlexibleArm.paper()
    t = np.linspace(0.0, 0.2, 201)
    torque = np.zeros((t.shape[0], 2))
    torque[:50, 0] = 5.0
    runs = [functools.partial(simulate_open_loop, arm, t, torque), {"arm": arm, "duration": 0.1}]
    out = flexarm.simulate_many(runs, workers=2)
    _assert_same(out[0], simulate_open_loop(arm, t, torque))
    _assert_same(out[1], simulate(arm, duration=0.1))


def test_failures_are_kept_per_run_or_raised():
    arm = FlexibleArm.paper()
    runs = [
        {"arm": arm, "duration": 0.1},
        {"arm": arm, "dt": 1e-3, "duration": 5.0, "check_sampling": False},  # diverges
        {"arm": arm, "duration": -1.0},  # a bad parameter
        {"arm": arm, "duration": 0.1, "rng": 3},
    ]
    out = simulate_many(runs, workers=2, errors="return")
    assert out[0].info["status"] == "ok" and out[3].info["status"] == "ok"
    assert isinstance(out[1], SimulationError) and out[1].result.t[-1] > 1.0
    assert isinstance(out[2], InvalidValueError) and "duration" in str(out[2])
    with pytest.raises(SimulationError):
        simulate_many([runs[0], runs[1], runs[3]], workers=2)


def test_iter_simulations_yields_every_index_once():
    arm = FlexibleArm.paper()
    runs = ({"arm": arm, "duration": 0.02 * (1 + i % 3)} for i in range(9))  # a generator
    seen = sorted(i for i, _ in iter_simulations(runs, workers=2))
    assert seen == list(range(9))


@pytest.mark.parametrize(
    "kw, error, needle",
    [
        ({"runs": [{"duration": 1.0}]}, InvalidTypeError, "arm"),
        ({"runs": [42]}, InvalidTypeError, "int"),
        ({"runs": [], "workers": 0}, InvalidValueError, "workers"),
        ({"runs": [], "workers": 1.5}, InvalidTypeError, "workers"),
        ({"runs": [], "errors": "ignore"}, InvalidValueError, "errors"),
    ],
)
def test_bad_batches_name_the_parameter(kw, error, needle):
    with pytest.raises(error, match=needle):
        simulate_many(**kw)


def test_an_empty_batch_is_empty():
    assert simulate_many([]) == []


def test_a_stop_flag_ends_a_run_between_chunks():
    import threading

    from flexarm.errors import Cancelled

    arm = FlexibleArm.paper()
    stop = threading.Event()
    stop.set()
    with pytest.raises(Cancelled):
        simulate(arm, duration=0.1, stop=stop)
    stop = threading.Event()
    timer = threading.Timer(0.3, stop.set)
    timer.start()
    with pytest.raises(Cancelled):  # 3000 s of simulated time: seconds of work
        simulate(arm, duration=3000.0, record_every=1000, stop=stop)
    timer.cancel()


def test_closing_a_batch_stops_its_runs(monkeypatch):
    """Runs in flight get the batch's stop flag, and closing the batch sets it."""
    from flexarm.sim import batch

    flags = []

    def spy(arm, **kw):
        flags.append(kw["stop"])
        return simulate(arm, **kw)

    monkeypatch.setattr(batch, "simulate", spy)
    arm = FlexibleArm.paper()
    runs = [{"arm": arm, "duration": 0.01}] + [
        {"arm": arm, "duration": 3000.0, "record_every": 1000} for _ in range(3)
    ]
    outcomes = iter_simulations(runs, workers=2)
    first = next(outcomes)
    outcomes.close()
    assert first[0] == 0 and len(flags) >= 2
    assert all(flag.is_set() for flag in flags)
