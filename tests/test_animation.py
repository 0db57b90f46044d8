"""Watching a run: the drawn arm is the arm's kinematics, the animation and the GIF
have their frames, old result files still animate, the CLI writes or refuses."""

from __future__ import annotations

import json
import pathlib

import numpy as np
import pytest
from PIL import Image

import flexarm as fa
from flexarm.cli import main
from flexarm.sensing.sensors import TipSensor
from flexarm.sim.animation import arm_outline, write_animation
from flexarm.sim.results import SimulationResult


@pytest.fixture(scope="module")
def run():
    arm = fa.FlexibleArm.paper(n_modes=2, joints=[fa.LinearJoint(2e4, 0.5)] * 2)
    return arm, fa.simulate(arm, duration=0.3, sensor=TipSensor(model="paper"))


def test_the_outline_is_the_arms_deflected_kinematics(run):
    arm, res = run
    rows = np.arange(0, res.t.shape[0], 97)
    pts = arm_outline(res, rows)  # (rows, links, S, 2)
    assert pts.shape == (rows.shape[0], 2, 21, 2)
    np.testing.assert_allclose(pts[:, -1, -1], res.tip[rows], rtol=0, atol=1e-12)
    for link, s in ((0, 7), (1, 13)):  # inner points: the arm's own point_position
        d = arm.link_lengths[link] * s / 20
        expected = arm.point_position(res.q[rows], link, d)
        np.testing.assert_allclose(pts[:, link, s], expected, rtol=0, atol=1e-12)
    assert np.abs(res.link_deflections).max() > 1e-6  # the shapes are exercised


def test_animate_subsamples_to_the_frame_rate(run):
    from matplotlib.animation import FuncAnimation

    _, res = run
    anim = res.animate(fps=20)
    assert isinstance(anim, FuncAnimation)
    frames = list(anim.new_frame_seq())
    assert len(frames) == 7  # 0, 0.05, ..., 0.3 s
    artists = anim._func(3)
    assert any(getattr(a, "get_text", lambda: "")() == "t = 0.15 s" for a in artists)
    anim._draw_was_started = True  # (never shown: silence "deleted without rendering")


def test_a_gif_is_written_with_its_frames(run, tmp_path):
    _, res = run
    path = write_animation(res, tmp_path / "arm.gif", fps=10, dpi=40)
    with Image.open(path) as im:
        assert im.format == "GIF" and im.n_frames == 4 and im.size == (240, 240)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["arm.gif"]  # nothing left over


def test_results_saved_without_the_shapes_still_animate(run, tmp_path):
    _, res = run
    path = res.save(tmp_path / "run.npz")
    again = SimulationResult.load(path)
    np.testing.assert_array_equal(again.mode_shape_samples, res.mode_shape_samples)
    with np.load(path) as data:  # an older file: without the optional arrays
        old = {k: data[k] for k in data.files if k not in ("mode_shape_samples", "tip_slope_gains")}
    np.savez(tmp_path / "old.npz", **old)
    legacy = SimulationResult.load(tmp_path / "old.npz")
    assert legacy.mode_shape_samples is None
    pts = arm_outline(legacy, np.array([0, 100]))
    assert pts.shape == (2, 2, 2, 2)  # rigid links from the joint angles
    legacy.animate(fps=5)._draw_was_started = True


def test_cli_writes_a_gif(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    status = main(["simulate", "--duration", "0.1", "--animate", "arm.gif", "--json"])
    out, err = capsys.readouterr()
    assert status == 0 and not err
    assert json.loads(out)["animation"] == str(tmp_path / "arm.gif")
    with Image.open(tmp_path / "arm.gif") as im:
        assert im.n_frames == 3


@pytest.mark.parametrize(
    ("name", "which", "match"),
    [
        ("arm.mp4", None, "needs ffmpeg on PATH"),
        ("arm.avi", "/usr/bin/ffmpeg", "must end in .gif or .mp4"),
        ("nodir/arm.gif", None, "no such directory"),
    ],
)
def test_cli_refuses_before_simulating(capsys, tmp_path, monkeypatch, name, which, match):
    import flexarm.cli.simulate as cli

    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr(cli.shutil, "which", lambda _: which)
    monkeypatch.setattr("flexarm.sim.closed_loop.simulate", _never)
    status = main(["simulate", "--duration", "0.1", "--animate", name])
    out, err = capsys.readouterr()
    assert status == 2 and not out and match in err and len(err.strip().splitlines()) == 1
    assert err.startswith("flexarm simulate: error: argument --animate: ")
    assert list(pathlib.Path(tmp_path).iterdir()) == []


def _never(*args, **kwargs):  # pragma: no cover - the point is that it is not called
    raise AssertionError("simulated before checking --animate")


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda r, p: r.animate(fps=0.0), "'fps' parameter of animate"),
        (lambda r, p: r.animate(speed=-1.0), "'speed' parameter of animate"),
        (lambda r, p: write_animation(r, p / "x.png"), "must end in .gif or .mp4"),
    ],
)
def test_bad_input_is_named(run, tmp_path, call, match):
    with pytest.raises(ValueError, match=match):
        call(run[1], tmp_path)
