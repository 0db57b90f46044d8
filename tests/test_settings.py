"""SimulationSettings: one object carries a run, validated once; simulate's keywords
override its fields, and a keyword that is not a setting is refused by name."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.trajectories import Square
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.sensing.delays import DelayModel
from flexarm.sensing.sensors import JointSensor, TipSensor
from flexarm.sim.settings import SimulationSettings

ARM = fa.FlexibleArm.paper()
PATH = Square(center=(5.0, 0.0), side=2.0, time_per_side=0.5)


def _same(a, b):
    for name in ("t", "q", "dq", "tau", "tip", "measurement", "reference"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_settings_and_keywords_give_the_same_run():
    settings = SimulationSettings(
        sensor=JointSensor(noise_std=1e-4), duration=0.1, dt=1e-4, seed=5, record_every=3
    )
    by_object = fa.simulate(ARM, None, PATH, settings)
    by_keyword = fa.simulate(
        ARM,
        trajectory=PATH,
        sensor=JointSensor(noise_std=1e-4),
        duration=0.1,
        dt=1e-4,
        seed=5,
        record_every=3,
    )
    by_override = fa.simulate(ARM, None, PATH, settings.replace(dt=2e-4), dt=1e-4)
    _same(by_object, by_keyword)
    _same(by_object, by_override)
    assert by_object.info["dt_s"] == 1e-4 and by_object.info["record_every"] == 3


def test_rng_overrides_the_settings_seed():
    settings = SimulationSettings(sensor=JointSensor(noise_std=1e-3), duration=0.05, seed=1)
    seeded = fa.simulate(ARM, None, PATH, settings)
    same = fa.simulate(ARM, None, PATH, settings, rng=1)
    other = fa.simulate(ARM, None, PATH, settings, rng=2)
    _same(seeded, same)
    assert not np.array_equal(seeded.measurement, other.measurement)


def test_replace_validates_the_copy_and_leaves_the_original():
    s = SimulationSettings(dt=1e-4)
    t = s.replace(substeps=3, sensor=TipSensor())
    assert (s.substeps, t.substeps, t.dt) == (1, 3, 1e-4)
    assert isinstance(s.sensor, JointSensor) and isinstance(t.sensor, TipSensor)
    with pytest.raises(InvalidValueError, match="'substeps' parameter of SimulationSettings"):
        s.replace(substeps=0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.dt = 1.0  # type: ignore[misc]


def test_settings_normalise_what_they_are_given():
    s = SimulationSettings(
        delay=None, torque_limit=np.array([1, 2]), initial_state=np.zeros(4), dt=1
    )
    assert s.delay == DelayModel.none()
    assert s.torque_limit == (1.0, 2.0) and s.initial_state == (0.0,) * 4
    assert isinstance(s.dt, float) and SimulationSettings(torque_limit=3).torque_limit == 3.0


@pytest.mark.parametrize(
    ("changes", "error", "match"),
    [
        ({"dt": 0.0}, InvalidValueError, "'dt'"),
        ({"dt": "fast"}, InvalidTypeError, "'dt'"),
        ({"duration": -1.0}, InvalidValueError, "'duration'"),
        ({"substeps": 1.5}, InvalidTypeError, "'substeps'"),
        ({"record_every": 0}, InvalidValueError, "'record_every'"),
        ({"torque_limit": 0.0}, InvalidValueError, "'torque_limit'"),
        ({"torque_limit": [[1.0]]}, InvalidValueError, "'torque_limit'"),
        ({"torque_limit": float("nan")}, InvalidValueError, "'torque_limit'"),
        ({"initial_state": [[0.0]]}, InvalidValueError, "'initial_state'"),
        ({"initial_state": [np.nan]}, InvalidValueError, "'initial_state'"),
        ({"elbow": "up"}, InvalidValueError, "'elbow'"),
        ({"method": "euler"}, InvalidValueError, "'method'"),
        ({"max_deflection": 0.0}, InvalidValueError, "'max_deflection'"),
        ({"seed": -1}, InvalidValueError, "'seed'"),
        ({"smoothing": -0.1}, InvalidValueError, "'smoothing'"),
        ({"feedforward": 1}, InvalidTypeError, "'feedforward'"),
        ({"check_sampling": "yes"}, InvalidTypeError, "'check_sampling'"),
        ({"delay_reference": None}, InvalidTypeError, "'delay_reference'"),
        ({"sensor": "tip"}, InvalidTypeError, "'sensor'"),
        ({"delay": 0.1}, InvalidTypeError, "'delay'"),
        ({"shaper": "zv"}, InvalidTypeError, "'shaper'"),
        ({"method": "scipy", "record_every": 2}, InvalidValueError, "'method'"),
        (
            {"method": "scipy", "sensor": JointSensor(noise_std=1e-3)},
            InvalidValueError,
            "'method'",
        ),
    ],
)
def test_settings_refuse_bad_values_by_name(changes, error, match):
    with pytest.raises(error, match=match):
        SimulationSettings(**changes)
    with pytest.raises(error, match=match):  # the same check through simulate
        fa.simulate(ARM, **{"duration": 0.01, **changes})


@pytest.mark.parametrize("name", ["durration", "n_steps", "controller_state", "noise"])
def test_simulate_refuses_a_keyword_that_is_not_a_setting(name):
    with pytest.raises(InvalidTypeError, match=f"'{name}' is not a setting of a simulation"):
        fa.simulate(ARM, **{name: 1.0})
    with pytest.raises(InvalidTypeError, match=f"'{name}'"):
        SimulationSettings().replace(**{name: 1.0})


def test_simulate_refuses_settings_of_another_type():
    with pytest.raises(InvalidTypeError, match="'settings' parameter of simulate"):
        fa.simulate(ARM, None, None, {"dt": 1e-4})  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("changes", "match"),
    [
        ({"torque_limit": (1.0, 2.0, 3.0)}, "'torque_limit' parameter of simulate"),
        ({"initial_state": (0.0,) * 3}, "'initial_state'"),
        ({"duration": 1e-5}, "at least one control period"),
    ],
)
def test_what_depends_on_the_arm_is_checked_by_the_simulator(changes, match):
    settings = SimulationSettings(**changes)  # fine on its own
    with pytest.raises(InvalidValueError, match=match):
        fa.simulate(ARM, None, PATH, settings)


def test_a_scenario_carries_its_settings():
    from flexarm.sim.scenario import Scenario

    s = Scenario.from_dict(
        {
            "sensor": {"kind": "joint", "noise_std": 1e-4},
            "simulation": {"duration": 0.05, "dt": 1e-4, "seed": 3},
        }
    )
    assert s.sensor is s.simulation.sensor and s.sensor.noise_std == 1e-4
    assert (s.simulation.duration, s.simulation.dt, s.simulation.seed) == (0.05, 1e-4, 3)
    _same(s.simulate(), fa.simulate(s.arm, s.controller, s.trajectory, s.simulation))
