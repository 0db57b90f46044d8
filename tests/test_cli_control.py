"""The new controllers and sensor model from scenario files and the command line."""

from __future__ import annotations

import json

import pytest

import flexarm as fa
from flexarm.control.lqg import LQG
from flexarm.control.reflected import ReflectedTipPD
from flexarm.errors import ScenarioError
from flexarm.sim.scenario import Scenario
from helpers.cli import error_line, run


def test_scenario_builds_lqg_reflected_and_the_paper_sensor():
    s = Scenario.from_dict(
        {
            "sensor": {"kind": "tip", "model": "paper"},
            "controller": {"kind": "lqg", "position_weight": 2e4, "model_modes": 2},
            "simulation": {"smoothing": 0.1, "feedforward": True, "check_sampling": False},
        }
    )
    assert isinstance(s.controller, LQG) and s.controller.position_weight == 2e4
    assert s.controller.model is not None and s.controller.model.n_modes == (2, 2)
    assert s.sensor.model == "paper"
    run = s.simulation
    assert run.smoothing == 0.1 and run.feedforward is True and run.check_sampling is False
    assert s.simulate_kwargs()["settings"] is run
    r = Scenario.from_dict(
        {"sensor": {"kind": "tip"}, "controller": {"kind": "reflected", "alpha": 0.6}}
    )
    assert isinstance(r.controller, ReflectedTipPD) and r.controller.alpha == 0.6


@pytest.mark.parametrize(
    ("data", "key"),
    [
        ({"controller": {"kind": "lqg", "weight": 1.0}}, "controller.weight"),
        ({"controller": {"kind": "lqg", "torque_weight": -1.0}}, "controller.torque_weight"),
        ({"controller": {"kind": "reflected", "alpha": 3.0}}, "controller.alpha"),
        ({"sensor": {"kind": "tip", "model": "rigid"}}, "sensor.model"),
        ({"simulation": {"smoothing": -0.1}}, "simulation.smoothing"),
        ({"simulation": {"check_sampling": "no"}}, "simulation.check_sampling"),
    ],
)
def test_scenario_errors_name_the_key(data, key):
    with pytest.raises(ScenarioError) as err:
        Scenario.from_dict(data, source="s.toml")
    assert key in str(err.value)


def test_cli_lqg_on_the_tip_sensor(capsys):
    status, out, err = run(
        capsys,
        "simulate",
        "--controller",
        "lqg",
        "--sensor",
        "tip",
        "--smoothing",
        "0.1",
        "--duration",
        "6",
        "--json",
    )
    assert status == 0, err
    data = json.loads(out)
    assert data["settings"]["controller"]["kind"] == "lqg"
    assert data["run"]["feedforward"] is True and data["run"]["smoothing_s"] == 0.1
    assert data["rms_error_m"] < 0.05


def test_cli_paper_sensor_model(capsys):
    status, out, err = run(
        capsys,
        "simulate",
        "--sensor",
        "point:1:0.5",
        "--sensor-model",
        "paper",
        "--duration",
        "0.5",
        "--json",
    )
    assert status == 0, err
    data = json.loads(out)
    assert data["settings"]["sensor"]["model"] == "paper"
    assert data["run"]["sensor"] == "point:1:0.5 (paper model)"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--sensor-model", "rigid"], "--sensor-model"),
        (["--smoothing", "-1"], "--smoothing"),
        (["--controller", "reflected"], "'sensor'"),  # reflected needs a point sensor
    ],
)
def test_cli_bad_input(capsys, argv, needle):
    status, out, err = run(capsys, "simulate", *argv, "--duration", "0.1")
    assert status == 2 and out == ""
    assert needle in error_line(err)


def test_paper_arm_three_modes_refused_with_the_period_that_works(capsys):
    status, _, err = run(capsys, "simulate", "--scenario", "/dev/null", "--duration", "0.1")
    assert status == 0, err  # an empty scenario is the paper's arm: runs
    s = Scenario.from_dict({"arm": {"n_modes": 3}})
    with pytest.raises(ValueError, match=r"dt < 6\.3"):
        fa.simulate(s.arm, **s.simulate_kwargs())
