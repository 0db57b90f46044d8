"""``flexarm identify hammerstein``: a Hammerstein model from a data file, the robot
experiment, and one-line errors with status 2 and nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexarm
from flexarm.ident import HammersteinIdentifier, simulate_hammerstein
from flexarm.ident.hammerstein.systems import Saturation
from flexarm.studies.joint_identification import DriveNonlinearity
from helpers.cli import error_line, run


@pytest.fixture(scope="module")
def data(tmp_path_factory):
    """A saturation followed by a first-order ARMA, white uniform input."""
    rng = np.random.default_rng(7)
    u = rng.uniform(-2.0, 2.0, 8000)
    phi = Saturation(1.0)
    y = simulate_hammerstein(phi, [0.5], [1.0, 0.4], u, noise_std=0.05, rng=rng)
    path = tmp_path_factory.mktemp("ham") / "io.csv"
    np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="u,y", comments="")
    return path, phi


def test_fit_with_two_known_points_recovers_the_nonlinearity(capsys, tmp_path, data):
    path, phi = data
    out = tmp_path / "r"
    argv = ("identify", "hammerstein", path, "--x", "u", "--y", "y")
    status, stdout, err = run(capsys, *argv, "--known", "0:0,1.8:1", "--out", out, "--json")
    assert status == 0, err
    summary = json.loads(stdout)
    assert summary["normalisation"] == "two-point"
    x = np.array(summary["nonlinearity"]["x"])
    estimate = np.array(summary["nonlinearity"]["phi"])
    # the command is the library's identifier on the chosen columns, nothing more
    u, y = np.loadtxt(path, delimiter=",", skiprows=1, unpack=True)
    model = HammersteinIdentifier(known_points=((0.0, 0.0), (1.8, 1.0))).fit(u, y)
    np.testing.assert_allclose(estimate, model.nonlinearity(x), rtol=1e-12, atol=1e-12)
    assert summary["fit_percent"] == pytest.approx(model.fit_percent(u, y), rel=1e-12)
    assert summary["method"] == "white" and "looks white" in summary["reason"]
    assert summary["baseline"]["fit_percent"] == pytest.approx(model.baseline_.fit_percent(u, y))
    # which won on the validation part, and by how much: the library's comparison
    assert summary["comparison"] == model.report_.comparison.summary()
    assert summary["winner"] == model.report_.winner == "hammerstein"
    # two-point normalisation: the estimate passes through the known points (up to the
    # interpolation between grid points 0.02 apart), and has the saturation's shape
    assert np.interp([0.0, 1.8], x, estimate) == pytest.approx([0.0, 1.0], abs=0.02)
    assert np.corrcoef(estimate, phi(x))[0, 1] > 0.99
    ir = np.array(summary["impulse_response"])
    assert ir[0] == pytest.approx(1.0, abs=0.08) and ir[1] == pytest.approx(0.9, abs=0.1)
    assert sorted(p.name for p in out.iterdir()) == sorted(summary["files"])
    table = np.loadtxt(out / "nonlinearity.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 1], estimate, rtol=1e-10)
    lags = np.loadtxt(out / "impulse_response.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(lags[:, 0], np.arange(40))
    np.testing.assert_allclose(lags[:, 1], ir, rtol=1e-10)
    assert json.loads((out / "summary.json").read_text()) == summary


def test_without_known_points_the_text_says_affine(capsys, data):
    path, _ = data
    status, stdout, err = run(capsys, "identify", "hammerstein", path, "--lags", "20")
    assert status == 0, err
    assert "up to an affine map" in stdout and "fit" in stdout


def test_robot_experiment_writes_its_files(capsys, tmp_path):
    out = tmp_path / "robot"
    argv = ("identify", "hammerstein", "--duration", "20", "--seed", "1", "--out", out)
    status, stdout, err = run(capsys, *argv, "--json")
    assert status == 0, err
    summary = json.loads(stdout)
    assert summary["mode"] == "hammerstein-robot" and summary["seed"] == 1
    assert summary["duration_s"] == 20.0 and summary["info"]["n_holds"] == 2000
    # the tolerances the study states for a 20 s record (tests/test_joint_identification.py)
    assert summary["stiffness"]["rms_error"] < 0.1 and summary["stiffness"]["max_error"] < 1.0
    assert summary["friction"]["rms_error"] < 0.1 and summary["friction"]["max_error"] < 0.4
    assert summary["drive"]["relative_rms_error"] < 0.1
    ham = summary["hammerstein"]
    assert ham["fit_percent"] > 60 and ham["fit_percent"] > ham["reference_fit_percent"] - 10
    assert sorted(p.name for p in out.iterdir()) == sorted(summary["files"])
    # the files hold what the summary says, and the truth is the model's own law
    assert json.loads((out / "summary.json").read_text()) == summary
    with np.load(out / "curves.npz") as z:
        curves = {k: z[k] for k in z.files}
    for name in ("stiffness", "friction", "drive"):
        x, est, truth = (curves[f"{name}_{k}"] for k in ("x", "estimate", "truth"))
        ok = np.isfinite(est)
        rms = np.sqrt(np.mean((est[ok] - truth[ok]) ** 2))
        assert rms == pytest.approx(summary[name]["rms_error"], rel=1e-12)
        assert [x[0], x[-1]] == pytest.approx(summary[name]["grid"], rel=1e-12)
    np.testing.assert_allclose(
        curves["stiffness_truth"], flexarm.NonlinearJoint.default().torque(curves["stiffness_x"])
    )
    np.testing.assert_allclose(curves["drive_truth"], DriveNonlinearity()(curves["drive_x"]))
    np.testing.assert_allclose(curves["impulse_response"], ham["impulse_response"], rtol=1e-12)


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (("--order", "zero"), "--order"),
        (("--known", "0:0"), "--known"),
        (("--known", "a:b,c:d"), "--known"),
        (("--lags", "1"), "--lags"),
        (("--duration", "30"), "--duration"),
        (("--study",), "unrecognized arguments: --study"),
        (("--grid", "100"), "unrecognized arguments: --grid"),
        (("--x", "nope"), "nope"),
        (("--torque-sensor",), "--torque-sensor"),
        (("--method", "colour"), "--method"),
        (("--knots", "1"), "--knots"),
        (("--bootstrap", "5"), "--bootstrap"),
    ],
)
def test_bad_options_are_one_line_and_write_nothing(capsys, tmp_path, data, extra, match):
    path, _ = data
    out = tmp_path / "r"
    status, stdout, err = run(capsys, "identify", "hammerstein", path, *extra, "--out", out)
    assert status == 2 and stdout == ""
    assert match in error_line(err)
    assert err.startswith("flexarm identify hammerstein: error:")
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (("identify", "hammerstein", "--duration", "1"), "holds"),
        (("identify", "hammerstein", "--x", "u"), "--x"),
        (("identify", "hammerstein", "--known", "0:0,1:1"), "--known"),
        (("identify", "hammerstein", "--order", "2"), "--order: applies to DATA"),
        (("identify", "fit", "x.csv", "--lags", "5"), "unrecognized arguments: --lags"),
        (("identify", "fit", "x.csv", "--torque-sensor"), "unrecognized arguments: --torque"),
    ],
)
def test_option_combinations(capsys, argv, match):
    status, _, err = run(capsys, *argv)
    assert status == 2 and match in err and len(err.strip().splitlines()) == 1


def test_constant_input_is_a_clear_error(capsys, tmp_path):
    path = tmp_path / "flat.csv"
    np.savetxt(path, np.column_stack([np.ones(3000), np.arange(3000.0)]), delimiter=",")
    status, _, err = run(capsys, "identify", "hammerstein", path)
    assert status == 2 and "'u'" in err and "Traceback" not in err


def test_method_knots_and_bootstrap_options(capsys, tmp_path, data):
    path, _ = data
    out = tmp_path / "c"
    argv = ("identify", "hammerstein", path, "--x", "u", "--y", "y", "--method", "correlated")
    status, stdout, err = run(capsys, *argv, "--knots", "8", "--bootstrap", "10", "--seed", "4",
                              "--lags", "20", "--out", out, "--json")  # fmt: skip
    assert status == 0, err
    s = json.loads(stdout)
    assert s["method"] == "correlated" and "method='correlated' was asked for" in s["reason"]
    assert s["n_knots"] == 8 and s["structure"]["chosen_by"] == "held-out"  # the order is chosen
    assert s["whiteness"]["white"] and s["seed"] == 4
    assert s["bands"]["n_boot"] == 10 and s["baseline"]["order"] >= 1
    u, y = np.loadtxt(path, delimiter=",", skiprows=1, unpack=True)
    model = HammersteinIdentifier(n_lags=20, method="correlated", n_knots=8).fit(u, y)
    assert s["fit_percent"] == pytest.approx(model.fit_percent(u, y), rel=1e-12)
    header = (out / "nonlinearity.csv").read_text().splitlines()[0]
    assert header == "u,phi,phi_low,phi_high"
    status, text, err = run(capsys, *argv, "--lags", "20")
    assert status == 0 and "path: correlated input" in text and "linear ARX baseline" in text
    assert "validation: the Hammerstein model (order" in text and "beats the best linear" in text


def test_robot_experiment_designed_for_the_dead_band(capsys):
    status, stdout, err = run(capsys, "identify", "hammerstein", "--design", "--json")
    assert status == 0, err
    s = json.loads(stdout)
    assert s["design"]["dead_band_fraction"] == 0.5 and s["hammerstein"]["method"] == "correlated"
    assert s["duration_s"] == s["design"]["duration_s"] == s["info"]["duration_s"]
    assert abs(s["dead_band"]["half_width_positive_Nm"] - 2.0) <= 1.0
    status, _, err = run(capsys, "identify", "hammerstein", "--design", "--duration", "30")
    assert status == 2 and "--duration: not with --design" in err
