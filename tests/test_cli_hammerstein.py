"""``flexarm identify --hammerstein``: a Hammerstein model from a data file, the robot
experiment, and one-line errors with status 2 and nothing written."""

from __future__ import annotations

import json

import numpy as np
import pytest

from flexarm.cli import main
from flexarm.ident import HammersteinIdentifier, simulate_hammerstein
from flexarm.ident.systems import Saturation


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


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
    argv = ("identify", "--hammerstein", path, "--x", "u", "--y", "y")
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
    assert summary["fit_percent"] == pytest.approx(model.score(u, y), rel=1e-12)
    # two-point normalisation: the estimate passes through the known points (up to the
    # interpolation between grid points 0.02 apart), and has the saturation's shape
    assert np.interp([0.0, 1.8], x, estimate) == pytest.approx([0.0, 1.0], abs=0.02)
    assert np.corrcoef(estimate, phi(x))[0, 1] > 0.99
    ir = np.array(summary["impulse_response"])
    assert ir[0] == pytest.approx(1.0, abs=0.08) and ir[1] == pytest.approx(0.9, abs=0.1)
    assert sorted(p.name for p in out.iterdir()) == sorted(summary["files"])
    table = np.loadtxt(out / "nonlinearity.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(table[:, 1], estimate, rtol=1e-10)


def test_without_known_points_the_text_says_affine(capsys, data):
    path, _ = data
    status, stdout, err = run(capsys, "identify", "--hammerstein", path, "--lags", "20")
    assert status == 0, err
    assert "up to an affine map" in stdout and "fit" in stdout


def test_robot_experiment_writes_its_files(capsys, tmp_path):
    out = tmp_path / "robot"
    argv = ("identify", "--hammerstein", "--duration", "20", "--seed", "1", "--out", out)
    status, stdout, err = run(capsys, *argv, "--json")
    assert status == 0, err
    summary = json.loads(stdout)
    assert summary["mode"] == "hammerstein-robot" and summary["seed"] == 1
    for curve in ("stiffness", "friction", "drive"):
        assert summary[curve]["rms_error"] >= 0.0
    assert sorted(p.name for p in out.iterdir()) == sorted(summary["files"])


@pytest.mark.parametrize(
    ("extra", "match"),
    [
        (("--order", "zero"), "--order"),
        (("--known", "0:0"), "--known"),
        (("--known", "a:b,c:d"), "--known"),
        (("--lags", "1"), "--lags"),
        (("--duration", "30"), "--duration"),
        (("--study",), "--study"),
        (("--grid", "100"), "--grid"),
        (("--x", "nope"), "nope"),
    ],
)
def test_bad_options_are_one_line_and_write_nothing(capsys, tmp_path, data, extra, match):
    path, _ = data
    out = tmp_path / "r"
    status, _, err = run(capsys, "identify", "--hammerstein", path, *extra, "--out", out)
    assert status == 2
    assert match in err and len(err.strip().splitlines()) == 1
    assert not out.exists()


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (("identify", "--hammerstein", "--duration", "1"), "holds"),
        (("identify", "--hammerstein", "--x", "u"), "--x"),
        (("identify", "--hammerstein", "--known", "0:0,1:1"), "--known"),
        (("identify", "--lags", "5", "x.csv"), "--hammerstein only"),
        (("identify", "--torque-sensor", "x.csv"), "--hammerstein only"),
    ],
)
def test_option_combinations(capsys, argv, match):
    status, _, err = run(capsys, *argv)
    assert status == 2 and match in err


def test_constant_input_is_a_clear_error(capsys, tmp_path):
    path = tmp_path / "flat.csv"
    np.savetxt(path, np.column_stack([np.ones(3000), np.arange(3000.0)]), delimiter=",")
    status, _, err = run(capsys, "identify", "--hammerstein", path)
    assert status == 2 and "'u'" in err and "Traceback" not in err
