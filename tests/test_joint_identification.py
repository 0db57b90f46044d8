"""Identifying the simulated robot joint (paper §IX): estimates against the true curves."""

from __future__ import annotations

import json
import re
import subprocess
import sys

import matplotlib
import numpy as np
import pytest

import flexarm
from flexarm.studies.joint_identification import (
    DriveNonlinearity,
    JointExcitation,
    JointSensors,
    identify_joint,
    joint_test_arm,
)
from flexarm.studies.joint_identification.experiment import run_excitation

matplotlib.use("Agg")

SHORT = JointExcitation(duration=20.0)


@pytest.fixture(scope="module")
def result():
    return identify_joint(excitation=SHORT, rng=0)


def test_the_experiment_applies_the_held_drive_map_open_loop():
    ex = JointExcitation(duration=1.0)  # 5000 periods of 0.2 ms, holds of 50 periods
    rec = run_excitation(joint_test_arm(), ex, np.random.default_rng(0))
    assert rec.command.shape == (101,) and rec.n_holds == 100 and rec.q.shape == (5001,)
    k = np.arange(5001)
    np.testing.assert_array_equal(rec.tau, ex.drive(rec.command[k // 50]))
    assert rec.q[0] == rec.q_m[0] == rec.v[0] == rec.v_m[0] == 0.0  # from rest
    assert rec.status == "ok"


def test_stiffness_curve_and_soft_windup(result):
    s = result.stiffness
    joint = flexarm.NonlinearJoint.default()
    np.testing.assert_allclose(s.truth, joint.torque(s.x))  # the truth is the model's law
    assert s.x[0] < -5e-3 and s.x[-1] > 5e-3  # the cubic part is reached
    assert s.rms_error < 0.1 and s.max_error < 1.0  # N m, over about +-170 N m
    w = result.windup
    # true secant stiffness near zero and outside the windup region, from the closed form
    inner, width = 5e-5, 1 / np.sqrt(joint.asw)
    k_in = (joint.torque(inner) - joint.torque(-inner)) / (2 * inner)
    k_out = (joint.torque(4 * width) - joint.torque(2 * width)) / (2 * width)
    assert w["stiffness_inside_true"] == pytest.approx(k_in, rel=0.05)  # grid interpolation
    assert w["stiffness_outside_true"] == pytest.approx(k_out, rel=0.01)
    assert w["stiffness_inside_estimate"] == pytest.approx(w["stiffness_inside_true"], rel=0.2)
    assert w["stiffness_outside_estimate"] == pytest.approx(k_out, rel=0.02)
    # resolved: the estimate is less than half as stiff inside the windup region as outside
    assert w["stiffness_inside_estimate"] < 0.5 * w["stiffness_outside_estimate"]


def test_friction_curve(result):
    f = result.friction
    friction = flexarm.MakkarFriction.default()
    np.testing.assert_allclose(f.truth, friction(f.x))
    assert f.x[0] < -0.2 and f.x[-1] > 0.2
    assert f.rms_error < 0.1 and f.max_error < 0.4  # N m; static level 1.5 N m
    # Stribeck hump: the peak is found near its true height
    assert np.nanmax(f.estimate) == pytest.approx(np.max(f.truth), abs=0.1)


def test_hammerstein_part(result):
    d = result.drive
    np.testing.assert_allclose(d.truth, DriveNonlinearity()(d.x))
    assert d.relative_rms_error < 0.1
    # the two-point normalisation from the drive's data sheet holds exactly
    np.testing.assert_allclose(
        result.hammerstein.nonlinearity([0.0, 48.0]), [0.0, 40.0], atol=1e-10
    )
    # free run on held-out data: close to what the true drive map with a fitted FIR achieves
    assert result.fit_percent > 60
    assert result.fit_percent > result.reference_fit_percent - 10
    v = result.validation
    assert v["y"].shape == v["y_hat"].shape == v["u"].shape == (667,)


def test_torque_sensor_measures_the_windup_better():
    res = identify_joint(excitation=SHORT, torque_measurement="sensor", rng=0)
    w = res.windup
    assert w["stiffness_inside_estimate"] == pytest.approx(w["stiffness_inside_true"], rel=0.05)
    assert res.stiffness.rms_error < 0.05


def test_linear_frictionless_joint_is_an_exact_hammerstein_plant():
    arm = joint_test_arm(flexarm.LinearJoint(1e4, 0.3, motor_damping=10.0))
    res = identify_joint(arm, excitation=SHORT, sensors=JointSensors(0, 0, 0, 0, 0), rng=1)
    assert res.windup == {}
    np.testing.assert_allclose(res.stiffness.truth, 1e4 * res.stiffness.x)
    assert res.stiffness.relative_rms_error < 2e-4  # noise-free: discretisation and smoothing
    assert res.friction.rms_error < 0.05 and np.all(res.friction.truth == 0)
    assert res.reference_fit_percent > 95  # linear plant + drive map: Hammerstein exactly
    assert res.summary()["friction"]["relative_rms_error"] is None


def test_the_plot_reads_at_two_columns_and_saves_in_any_format(result, tmp_path, assert_readable):
    from flexarm.figures import DOUBLE_COLUMN
    from flexarm.studies.joint_identification.result import saved_files

    assert_readable(result.plot(), DOUBLE_COLUMN)
    paths = result.save(tmp_path, figure_format="svg")
    assert [p.name for p in paths] == list(saved_files("svg"))
    assert paths[-1].read_bytes().startswith(b"<?xml")


def test_summary_plot_and_save(result, tmp_path):
    summary = result.summary()
    assert json.loads(json.dumps(summary)) == summary
    assert summary["info"]["n_holds"] == 2000 and summary["info"]["hold_s"] == pytest.approx(0.01)
    fig = result.plot()
    assert len(fig.axes) >= 4
    for ax in fig.axes[:4]:  # the four panels: "quantity (unit)" on both axes
        assert re.match(r"^\S.* \([^()]+\)$", ax.get_xlabel()), ax.get_xlabel()
        assert re.match(r"^\S.* \([^()]+\)$", ax.get_ylabel()), ax.get_ylabel()
    from matplotlib.figure import Figure

    given = Figure()
    assert result.plot(given) is given and len(given.axes) >= 4
    paths = result.save(tmp_path / "out")
    assert [p.name for p in paths] == ["summary.json", "curves.npz", "identify_joint.png"]
    with np.load(paths[1]) as z:
        np.testing.assert_array_equal(z["stiffness_estimate"], result.stiffness.estimate)
    import matplotlib.pyplot as plt

    plt.close("all")


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"arm": flexarm.FlexibleArm.paper()}, ValueError, "'arm' parameter of identify_joint"),
        ({"arm": 3}, TypeError, "'arm' parameter of identify_joint must be a FlexibleArm"),
        ({"torque_measurement": "strain"}, ValueError, "'torque_measurement' parameter"),
        ({"excitation": JointExcitation(duration=1.0)}, ValueError, "'excitation' parameter"),
        ({"excitation": "long"}, TypeError, "'excitation' parameter .* JointExcitation"),
        ({"validation_fraction": 1.5}, ValueError, "'validation_fraction' parameter"),
        ({"quasi_static_fraction": 0.0}, ValueError, "'quasi_static_fraction' parameter"),
        ({"friction_window": 0}, ValueError, "'friction_window' parameter"),
        ({"rng": "seed"}, TypeError, "'rng' parameter of identify_joint"),
        ({"method": "colour"}, ValueError, "'method' parameter of identify_joint"),
    ],
)
def test_bad_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        identify_joint(**kwargs)


def test_parameter_classes_validate():
    with pytest.raises(ValueError, match="'hold' parameter of JointExcitation"):
        JointExcitation(hold=1e-5)
    with pytest.raises(ValueError, match="'limit' parameter of DriveNonlinearity"):
        DriveNonlinearity(limit=0.0)
    with pytest.raises(ValueError, match="'rate_noise' parameter of JointSensors"):
        JointSensors(rate_noise=-1.0)
    with pytest.raises(ValueError, match="'dead_band_fraction' parameter of JointExcitation"):
        JointExcitation(dead_band_fraction=1.0)
    with pytest.raises(ValueError, match="'dead_band_span' parameter of JointExcitation"):
        JointExcitation(dead_band_span=100.0)
    from flexarm.studies.joint_identification import design_dead_band_excitation

    with pytest.raises(ValueError, match="'fraction' parameter of design_dead_band_excitation"):
        design_dead_band_excitation(fraction=1.0)
    with pytest.raises(TypeError, match="'pilot' parameter of design_dead_band_excitation"):
        design_dead_band_excitation(pilot=3)


def test_example_script(tmp_path, capsys):
    import importlib.util
    import pathlib

    path = pathlib.Path(__file__).resolve().parents[1] / "examples" / "identify_joint.py"
    spec = importlib.util.spec_from_file_location("identify_joint_example", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    assert module.main(["--duration", "20", "--out", str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert "soft windup" in out and "Hammerstein model" in out
    assert (tmp_path / "identify_joint.png").stat().st_size > 0
    assert module.main(["--duration", "2"]) == 2  # too short: one line on stderr
    assert "at least 300 holds" in capsys.readouterr().err
    assert module.main(["--design"]) == 0  # the experiment sized for the dead band
    out = capsys.readouterr().out
    assert out.startswith("design: 50 % of the commands") and "correlated path" in out
    assert "dead band: half-width" in out
    import matplotlib.pyplot as plt

    plt.close("all")


def test_settings_load_no_simulator():
    code = (
        "import sys\n"
        "from flexarm.studies.joint_identification import JointExcitation, JointSensors\n"
        "JointExcitation(duration=1.0), JointSensors()\n"
        "heavy = [m for m in sys.modules if m.split('.')[0] in ('numba', 'matplotlib')]\n"
        "assert not heavy, heavy\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr


def test_designed_excitation_resolves_the_dead_band():
    """The drive's +-2 N m dead band is not resolved by 60 s of uniform commands; an
    excitation sized for it (design module) resolves it: both half-widths within half the
    dead band of the truth (the resolution the design asks for), and the RMS error within
    +-3 dead-band widths below a quarter of the dead band."""
    from flexarm.studies.joint_identification import design_dead_band_excitation

    pilot_rng, main_rng = np.random.default_rng(0).spawn(2)
    design = design_dead_band_excitation(rng=pilot_rng)
    ex, delta = design.excitation, 2.0
    # the design's arithmetic (module docstring), recomputed from its pilot figures
    c = 3 * delta
    share = 0.5 + 0.5 * c / 60.0
    assert ex.dead_band_fraction == 0.5 and ex.dead_band_span == c
    assert design.n_knots - 1 == int(np.ceil(2 * c / (share * delta / 2)))
    sigma, gain = design.pilot["sigma"], design.pilot["gain"]
    n_est = int(np.ceil(np.sqrt(3) * (design.n_knots - 1) * sigma**2 / (0.2**2 * gain**2)))
    assert design.n_holds == n_est and not design.capped
    assert ex.duration == np.ceil(np.ceil(n_est * 1.5) * 0.01)
    res = identify_joint(excitation=ex, method="correlated", rng=main_rng)
    db = res.dead_band
    for side in ("positive", "negative"):
        assert abs(db[f"half_width_{side}_Nm"] - delta) <= delta / 2, db
    assert db["rms_error_Nm"] <= delta / 4, db
    assert res.hammerstein.method_ == "correlated"
    # the uniform experiment of 60 s: no dead band in the estimate
    uniform = identify_joint(excitation=JointExcitation(duration=60.0), rng=0).dead_band
    assert uniform["rms_error_Nm"] > delta / 4
    assert max(uniform["half_width_positive_Nm"], uniform["half_width_negative_Nm"]) < delta / 2


def test_dead_band_summary_reads_a_known_curve():
    from flexarm.studies.joint_identification.estimation import dead_band_summary

    drive = DriveNonlinearity(2.0, 40.0)
    exact = dead_band_summary(drive, drive, 6.0)
    assert exact["rms_error_Nm"] == 0.0 and exact["half_width_positive_Nm"] == pytest.approx(2.0)
    assert exact["half_width_negative_Nm"] == pytest.approx(2.0)
    assert exact["slope_positive"] == pytest.approx(1.0)
    shifted = dead_band_summary(DriveNonlinearity(1.0, 40.0), drive, 6.0)
    assert shifted["half_width_positive_Nm"] == pytest.approx(1.0)
    assert shifted["max_error_Nm"] == pytest.approx(1.0)
