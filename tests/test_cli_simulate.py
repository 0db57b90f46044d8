"""``flexarm simulate`` and the scenario files behind it: output, overrides, delays,
one-line errors with status 2 and no files, divergence with status 1."""

from __future__ import annotations

import json
import math
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import flexarm as fa
from flexarm._io import json_ready
from flexarm.model.joints import MakkarFriction
from flexarm.sensing.delays import SEED_WAVE_SPEED, bending_group_speed, travel_delay
from flexarm.sim import simulate
from flexarm.sim.results import RESULT_FILES, SimulationResult
from flexarm.sim.scenario import Scenario, load_scenario
from flexarm.sim.scenario_schema import ScenarioError, apply_overrides
from helpers.cli import error_line, help_text, run, strict_json

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "paper_square.toml"
FILES = {"result.npz", "summary.json", "timeseries.csv", "tracking.png"}
REQUIRED = ("rms_error_m", "max_error_m", "sim_time_s", "wall_time_s")


def run_json(capsys, *argv):
    status, out, err = run(capsys, *argv, "--json")
    assert status == 0, err
    return strict_json(out)


@pytest.fixture(scope="module")
def paper():
    return fa.FlexibleArm.paper()


# ------------------------------------------------------------------ summary
def test_json_summary_has_the_metrics_and_the_settings(capsys, paper):
    data = run_json(capsys, "simulate", "--duration", "0.5")
    assert data["status"] == "ok"
    for key in (*REQUIRED, "corner_errors_m", "residual_vibration_m", "max_torque_Nm"):
        assert key in data
    assert 0 < data["rms_error_m"] <= data["max_error_m"] < 1.0
    assert data["sim_time_s"] == pytest.approx(0.5, abs=1e-12)
    assert data["wall_time_s"] > 0
    # every corner of the 20 s square comes after the end of this run: undefined, null
    assert data["corner_errors_m"] == [None] * 4
    s = data["settings"]
    w1 = paper.link_frequencies[0][0]
    assert s["controller"] == {"kind": "pd", "zeta": 0.707, "kp": w1**2, "kd": 2 * 0.707 * w1}
    assert s["sensor"]["spec"] == "joint"
    assert s["trajectory"]["kind"] == "square" and s["trajectory"]["side"] == 4.0
    assert s["simulation"]["dt"] == 2e-4 and s["simulation"]["duration"] == 0.5
    assert s["delay"]["delay_s"] == 0.0 and s["shaper"] == {"kind": "none"}
    assert data["run"]["controller"] == "pd" and data["run"]["status"] == "ok"


METRICS = (
    "rms_error_m",
    "max_error_m",
    "corner_errors_m",
    "residual_vibration_m",
    "settling_time_s",
    "control_effort_N2m2s",
    "max_torque_Nm",
    "sim_time_s",
)


def test_json_prints_the_summary_not_the_series(capsys, paper):
    """The summary's shape; its metrics bit for bit those of the Python call (JSON
    round-trips a float exactly; undefined metrics are null); the measurement and
    the reference, which nothing printed reads, are not recorded."""
    data = run_json(capsys, "simulate", "--duration", "24")
    top = {"status", *METRICS, "wall_time_s", "settings", "run", "out", "files", "animation"}
    assert set(data) == top  # no "series"
    assert data["run"]["record_signals"] is False
    want = json.loads(json.dumps(json_ready(simulate(paper, duration=24.0).metrics())))
    for key in METRICS:
        assert data[key] == want[key], key
    assert None not in data["corner_errors_m"]  # (all four corners inside the run)


def test_json_series_prints_every_recorded_column(capsys, paper):
    data = run_json(capsys, "simulate", "--duration", "0.05", "--series")
    assert data["run"]["record_signals"] is True
    header, table = simulate(paper, duration=0.05).table()
    assert list(data["series"]) == header and "x_ref" in header
    for name, column in zip(header, table.T, strict=True):
        assert data["series"][name] == column.tolist(), name
    for key in METRICS:  # the summary is the same
        assert key in data
    status, out, err = run(capsys, "simulate", "--duration", "0.05", "--series")
    assert status == 2 and out == "" and "--series" in err and "--json" in err


def test_text_summary(capsys):
    status, out, err = run(capsys, "simulate", "--duration", "0.2")
    assert status == 0 and err == ""
    assert "rms error" in out and "max torque" in out and "0.2 s" in out


def test_out_writes_exactly_the_promised_files(capsys, tmp_path):
    out_dir = tmp_path / "run"
    status, out, err = run(capsys, "simulate", "--duration", "0.5", "--out", out_dir, "--json")
    assert status == 0, err
    summary = strict_json(out)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]  # no temporary left behind
    assert {p.name for p in out_dir.iterdir()} == FILES
    assert strict_json((out_dir / "summary.json").read_text()) == summary
    assert summary["out"] == str(out_dir) and set(summary["files"]) == FILES

    res = SimulationResult.load(out_dir / "result.npz")
    assert summary["run"]["record_signals"] is True  # the files hold the whole run
    assert res.measurement.shape[1] > 0 and res.reference.shape[1] > 0
    metrics = res.metrics()
    for key in ("rms_error_m", "max_error_m", "sim_time_s", "control_effort_N2m2s"):
        assert metrics[key] == pytest.approx(summary[key], rel=1e-12)

    with open(out_dir / "timeseries.csv") as fh:
        header = fh.readline().strip().split(",")
    table = np.loadtxt(out_dir / "timeseries.csv", delimiter=",", skiprows=1)
    assert header[0] == "t" and header[-1] == "error"
    assert table.shape == (res.t.size, len(header))
    np.testing.assert_allclose(table[:, 0], res.t, rtol=1e-9)
    np.testing.assert_allclose(table[:, header.index("error")], res.error, rtol=1e-8, atol=1e-12)
    np.testing.assert_allclose(table[:, header.index("tau2")], res.tau[:, 1], rtol=1e-8)
    assert (out_dir / "tracking.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_out_may_be_an_empty_directory_but_never_a_full_one(capsys, tmp_path):
    empty = tmp_path / "empty"
    empty.mkdir()
    status, _, err = run(capsys, "simulate", "--duration", "0.1", "--out", empty)
    assert status == 0, err
    assert {p.name for p in empty.iterdir()} == FILES
    before = {p.name: p.stat().st_mtime_ns for p in empty.iterdir()}
    status, out, err = run(capsys, "simulate", "--duration", "0.1", "--out", empty)
    assert status == 2 and out == ""
    assert len(err.strip().splitlines()) == 1 and "--out" in err
    assert {p.name: p.stat().st_mtime_ns for p in empty.iterdir()} == before
    status, _, err = run(capsys, "simulate", "--out", tmp_path / "no" / "such")
    assert status == 2 and "does not exist" in err


# ------------------------------------------------------------------ scenarios
def test_the_example_scenario_runs(capsys):
    data = run_json(capsys, "simulate", "--scenario", EXAMPLE)
    assert data["settings"]["source"] == str(EXAMPLE)
    assert data["sim_time_s"] == pytest.approx(20.0)
    assert data["settings"]["trajectory"]["kind"] == "square"
    assert all(x is not None for x in data["corner_errors_m"])  # the whole square ran
    assert data["rms_error_m"] <= data["max_error_m"]


def test_the_example_scenario_spells_out_the_defaults():
    example = load_scenario(EXAMPLE).description
    default = Scenario.from_dict({}).description
    example.pop("source"), default.pop("source")
    assert example == default


SCENARIO = """
[trajectory]
kind = "circle"
center = [5.0, 1.0]
radius = 1.0
period = 2.0

[sensor]
noise_std = 1e-4

[controller]
kind = "joint-pd"
kp = [400.0, 300.0]
kd = 30.0

[simulation]
duration = 0.3
dt = 1e-4
seed = 3
"""


def test_a_scenario_overrides_the_defaults_and_options_override_the_scenario(capsys, tmp_path):
    path = tmp_path / "scenario.toml"
    path.write_text(SCENARIO)
    data = run_json(capsys, "simulate", "--scenario", path)
    s = data["settings"]
    assert s["trajectory"]["kind"] == "circle" and s["trajectory"]["center"] == [5.0, 1.0]
    assert s["controller"] == {"kind": "joint-pd", "kp": [400.0, 300.0], "kd": 30.0}
    assert s["sensor"]["noise_std"] == 1e-4
    assert s["simulation"]["dt"] == 1e-4 and s["simulation"]["seed"] == 3
    assert data["sim_time_s"] == pytest.approx(0.3, abs=1e-12)
    assert data["run"]["controller"] == "joint-pd" and data["run"]["dt_s"] == 1e-4

    data = run_json(
        capsys, "simulate", "--scenario", path, "--controller", "pd", "--duration", "0.2"
    )
    s = data["settings"]
    assert s["controller"]["kind"] == "pd" and s["controller"]["zeta"] == 0.707
    assert data["sim_time_s"] == pytest.approx(0.2, abs=1e-12)
    assert s["simulation"]["dt"] == 1e-4  # still from the file
    assert s["trajectory"]["kind"] == "circle"

    # a new sensor kind keeps the file's noise
    data = run_json(capsys, "simulate", "--scenario", path, "--sensor", "point:1:0.5")
    assert data["settings"]["sensor"]["spec"] == "point:1:0.5"
    assert data["settings"]["sensor"]["noise_std"] == 1e-4

    # the file's seed makes the encoder noise reproducible; --seed changes it
    argv = ("simulate", "--scenario", path, "--duration", "0.1")
    first, again = run_json(capsys, *argv), run_json(capsys, *argv)
    other = run_json(capsys, *argv, "--seed", "4")
    assert again["rms_error_m"] == first["rms_error_m"]
    assert other["rms_error_m"] != first["rms_error_m"]
    assert other["settings"]["simulation"]["seed"] == 4


def test_scenario_builds_custom_arms_and_flexible_joints():
    s = Scenario.from_dict(
        {
            "arm": {
                "links": [
                    {"length": 1.0, "flexural_rigidity": 5.0, "linear_density": 1.1, "n_modes": 2},
                    {"length": 0.8, "flexural_rigidity": 2.0, "linear_density": 0.6},
                ],
                "payload_mass": 0.3,
                "joints": {"kind": "nonlinear", "a1": 2e4, "friction": {"g6": 0.7}},
                "geometric_stiffening": False,
            },
            "trajectory": {"kind": "line", "start": [1.2, 0.3], "end": [1.0, 0.8], "duration": 1},
        }
    )
    # a link without n_modes gets Link's default; the arm, FlexibleArm's boundary default
    default_modes = fa.Link(0.8, 2.0, 0.6).n_modes
    assert s.arm.n_modes == (2, default_modes) and s.arm.payload_mass == 0.3
    assert s.arm.boundary == fa.FlexibleArm(s.arm.links).boundary
    assert s.arm.geometric_stiffening is False
    assert s.arm.has_flexible_joints and s.arm.joints[1].a1 == 2e4
    assert s.arm.joints[0].friction.g6 == 0.7
    assert s.arm.joints[0].friction.g1 == MakkarFriction.default().g1
    assert s.simulation.duration == 1.0
    linear = Scenario.from_dict({"arm": {"joints": {"kind": "linear"}}})
    assert linear.arm.joints[0].friction is None and linear.arm.joints[0].stiffness == 1e4


def test_simulate_kwargs_run_the_library(paper):
    s = Scenario.from_dict({"simulation": {"duration": 0.1}, "shaper": {"kind": "zv"}})
    res = simulate(s.arm, **s.simulate_kwargs())
    assert res.t[-1] == pytest.approx(0.1) and res.info["shaper"] == "Shaper"


def test_overrides_drop_the_keys_of_another_kind():
    data = {"sensor": {"kind": "point", "link": 1, "distance": 0.5, "noise_std": 0.1}}
    assert apply_overrides(data, {"sensor": {"kind": "tip"}}) == {
        "sensor": {"kind": "tip", "noise_std": 0.1}
    }
    data = {"controller": {"kp": 1.0, "kd": 2.0, "kind": "jt-pd"}}
    assert apply_overrides(data, {"controller": {"kind": "jt-pd"}}) == data
    assert apply_overrides({}, {"delay": {"delay": "seed"}}) == {"delay": {"delay": "seed"}}


def test_scenario_errors_name_the_file_and_the_key():
    with pytest.raises(ScenarioError, match=r"^s\.toml: arm\.links\[1\]\.length: The 'length'"):
        Scenario.from_dict(
            {
                "arm": {
                    "links": [{"length": 1, "flexural_rigidity": 1, "linear_density": 1}] * 1
                    + [{"length": 0, "flexural_rigidity": 1, "linear_density": 1}]
                }
            },
            source="s.toml",
        )
    with pytest.raises(ScenarioError, match=r"missing key 'trajectory\.start'"):
        Scenario.from_dict({"trajectory": {"kind": "line"}})
    with pytest.raises(ScenarioError, match=r"arm\.preset: give either"):
        Scenario.from_dict({"arm": {"preset": "paper", "links": []}})
    with pytest.raises(ScenarioError, match=r"shaper\.tolerance: applies to kind = 'ei'"):
        Scenario.from_dict({"shaper": {"kind": "zv", "tolerance": 0.1}})


# ------------------------------------------------------------------ delays, shapers
def test_seed_and_dispersive_delays_over_the_path_along_the_links(capsys, paper):
    lengths = [lk.length for lk in paper.links]
    link0 = paper.links[0]
    w1 = float(paper.link_frequencies[0][0])
    base = ("simulate", "--controller", "joint-pd", "--duration", "0.05")

    data = run_json(capsys, *base, "--sensor", "tip", "--delay", "seed")
    d = data["settings"]["delay"]
    expected = travel_delay(lengths[0] + lengths[1], "seed")
    assert expected == pytest.approx(9.0 / 41783.0, rel=1e-4)
    assert d["delay_s"] == pytest.approx(expected, rel=1e-12)
    assert d["path_length_m"] == 9.0 and d["wave_speed_m_s"] == SEED_WAVE_SPEED
    assert data["run"]["delay_s"] == pytest.approx(expected, rel=1e-12)
    assert data["run"]["effective_delay_s"] == pytest.approx(2e-4)  # one sample (exact)

    data = run_json(
        capsys,
        *base,
        "--sensor",
        "point:1:0.5",
        "--delay",
        "dispersive",
        "--delay-method",
        "pade",
        "--pade-order",
        "3",
        "--delay-reference",
    )
    d = data["settings"]["delay"]
    c = 2.0 * math.sqrt(w1) * (link0.flexural_rigidity / link0.linear_density) ** 0.25
    expected = (lengths[0] + 0.5) / c
    assert expected == pytest.approx(0.085, abs=1e-3)  # about 59 m/s over 5 m
    assert d["delay_s"] == pytest.approx(expected, rel=1e-12)
    assert d["wave_speed_m_s"] == pytest.approx(
        bending_group_speed(w1, link0.flexural_rigidity, link0.linear_density), rel=1e-12
    )
    assert d["method"] == "pade" and d["order"] == 3 and d["reference"] is True
    assert data["run"]["effective_delay_s"] == pytest.approx(expected, rel=1e-12)
    assert data["run"]["delay_reference"] is True

    # joint encoders are collocated: no travel, no delay
    data = run_json(capsys, *base, "--delay", "seed")
    assert data["settings"]["delay"]["delay_s"] == 0.0


def test_shaper_is_designed_for_the_first_link_or_for_every_link(capsys, paper):
    w = [float(f[0]) for f in paper.link_frequencies]
    data = run_json(capsys, "simulate", "--duration", "0.1", "--shaper", "zv")
    sh = data["settings"]["shaper"]
    assert sh["modes"] == "first" and sh["frequencies_rad_s"] == [w[0]]
    assert sh["times_s"] == pytest.approx([0.0, math.pi / w[0]])
    data = run_json(
        capsys, "simulate", "--duration", "0.1", "--shaper", "zvd", "--shaper-modes", "all"
    )
    sh = data["settings"]["shaper"]
    assert sh["frequencies_rad_s"] == w
    assert sh["times_s"][-1] == pytest.approx(2 * (2 * math.pi / w[0]))  # two ZVDs in series


# ------------------------------------------------------------------ bad input
BAD_SCENARIOS = {
    "unknown key": ("[trajectory]\nsidee = 3.0\n", "unknown key 'trajectory.sidee'"),
    "unknown section": ("[trajectry]\nside = 3.0\n", "unknown section 'trajectry'"),
    "wrong type": ('[trajectory]\nside = "big"\n', "trajectory.side"),
    "malformed": ("[trajectory\nside = 3.0\n", "not valid TOML"),
    "bad link": (
        "[[arm.links]]\nlength = -1.0\nflexural_rigidity = 1.0\nlinear_density = 1.0\n",
        "arm.links[0].length",
    ),
    "key of another kind": ('[controller]\nkind = "joint-pd"\nzeta = 0.5\n', "controller.zeta"),
    "bad delay string": ('[delay]\ndelay = "later"\n', "delay.delay"),
    "bad joint kind": ('[arm.joints]\nkind = "elastic"\n', "arm.joints.kind"),
    "negative duration": ("[simulation]\nduration = -1.0\n", "simulation.duration"),
    "path outside the workspace": ("[trajectory]\ncenter = [20.0, 0.0]\n", "reachable"),
}
BAD_OPTIONS = [
    (["--duration", "-1"], "--duration"),
    (["--dt", "0"], "--dt"),
    (["--duration", "1e-5"], "control period"),
    (["--sensor", "elbow"], "elbow"),
    (["--sensor", "point:5:0.5"], "'link' parameter of PointSensor must be < 2"),
    (["--sensor", "point:1:9"], "distance"),
    (["--controller", "lqr"], "lqr"),
    (["--shaper", "zvdd"], "zvdd"),
    (["--delay", "soon"], "soon"),
    (["--delay", "-0.1"], "--delay"),
    (["--delay", "0.01", "--delay-method", "pade", "--pade-order", "0"], "--pade-order"),
    (["--substeps", "0"], "--substeps"),
    (["--seed", "-3"], "--seed"),
    (["--bogus"], "--bogus"),
]


def _assert_one_line_status_2(capsys, tmp_path, argv, needle, keep=()):
    out_dir = tmp_path / "out"
    status, out, err = run(capsys, "simulate", *argv, "--out", out_dir)
    assert status == 2
    assert out == ""
    line = error_line(err)
    assert needle in line
    assert not out_dir.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(keep)  # nothing written
    return line


@pytest.mark.parametrize(("argv", "needle"), BAD_OPTIONS, ids=lambda x: str(x))
def test_bad_options_are_one_line_with_status_2_and_no_files(capsys, tmp_path, argv, needle):
    _assert_one_line_status_2(capsys, tmp_path, argv, needle)


@pytest.mark.parametrize("case", sorted(BAD_SCENARIOS))
def test_bad_scenarios_are_one_line_naming_file_and_key(capsys, tmp_path, case):
    text, needle = BAD_SCENARIOS[case]
    path = tmp_path / "scenario.toml"
    path.write_text(text)
    line = _assert_one_line_status_2(
        capsys, tmp_path, ["--scenario", path], needle, keep=["scenario.toml"]
    )
    assert str(path) in line


def test_a_missing_scenario_file_is_one_line(capsys, tmp_path):
    line = _assert_one_line_status_2(
        capsys, tmp_path, ["--scenario", tmp_path / "absent.toml"], "no such file"
    )
    assert "absent.toml" in line


def test_an_option_overriding_a_file_is_blamed_on_the_option(capsys, tmp_path):
    path = tmp_path / "scenario.toml"
    path.write_text("[simulation]\ndt = 1e-4\n")
    line = _assert_one_line_status_2(
        capsys, tmp_path, ["--scenario", path, "--dt", "-1"], "--dt", keep=["scenario.toml"]
    )
    assert "scenario.toml" not in line


def test_a_diverging_run_exits_1_with_one_line_and_keeps_the_partial_run(capsys, tmp_path):
    out_dir = tmp_path / "out"
    status, out, err = run(
        capsys, "simulate", "--sensor", "tip", "--duration", "0.5", "--out", out_dir, "--json"
    )
    assert status == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err
    assert "diverged at t = " in lines[0] and str(out_dir) in lines[0]
    t = float(lines[0].split("t = ")[1].split()[0])
    assert 0 < t < 0.1
    summary = json.loads(out)
    assert summary["status"] == "diverged" and summary["diverged_at_s"] == pytest.approx(t)
    assert summary["rms_error_m"] is None and len(summary["last_state"]) == 8
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(RESULT_FILES)
    on_disk = json.loads((out_dir / "summary.json").read_text())
    assert on_disk["status"] == "diverged"
    kept = SimulationResult.load(out_dir / "result.npz")
    assert kept.info["status"] == "diverged" and kept.t[-1] == pytest.approx(t)


def _help_paragraph(capsys, name):
    """The paragraph of ``flexarm simulate --help`` that starts with ``name:``, one line."""
    text = help_text(capsys, "simulate")
    start = text.index(f"\n{name}: ") + 1
    end = text.find("\n\n", start)
    return " ".join(text[start : end if end > 0 else None].split())


@pytest.mark.parametrize("sensor", ["joint", "tip"], ids=["completed", "diverged"])
def test_the_help_says_what_an_ended_run_writes(capsys, tmp_path, sensor):
    """The files the help names are the files a completed and a diverged run write,
    and what it says of a diverged run's summary holds."""
    output = _help_paragraph(capsys, "output")
    named = set(re.findall(r"\b(\w+\.(?:npz|json|csv|png))\b", output))
    assert named == FILES
    assert 'its summary\'s status "diverged", its metrics null' in output
    status, _, err = run(
        capsys, "simulate", "--sensor", sensor, "--duration", "0.2", "--out", tmp_path / "out"
    )
    assert {p.name for p in (tmp_path / "out").iterdir()} == named
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    if sensor == "tip":
        assert status == 1 and summary["status"] == "diverged"
        assert summary["rms_error_m"] is None and summary["max_error_m"] is None
        exits = _help_paragraph(capsys, "exit status")
        assert (
            "1 the simulation diverged (one line on stderr with the time and where the "
            "partial run is kept)" in exits
        )
        assert len(err.strip().splitlines()) == 1 and str(tmp_path / "out") in err
    else:
        assert status == 0 and summary["status"] == "ok"


def test_bad_input_writes_nothing_as_the_help_says(capsys, tmp_path):
    assert "Bad input writes nothing." in _help_paragraph(capsys, "output")
    status, _, _ = run(capsys, "simulate", "--duration", "-1", "--out", tmp_path / "out")
    assert status == 2 and not (tmp_path / "out").exists()


def test_a_diverging_run_without_out_writes_nothing(capsys, tmp_path):
    status, out, err = run(capsys, "simulate", "--sensor", "tip", "--duration", "0.5")
    assert status == 1 and out == ""
    assert err.strip().endswith("; nothing written")
    assert list(tmp_path.iterdir()) == []


# ------------------------------------------------------------------ help, console script
def test_help_lists_simulate(capsys):
    assert "simulate" in help_text(capsys)


def test_simulate_help(capsys):
    text = " ".join(help_text(capsys, "simulate").split())  # help wraps lines
    for needle in ("--scenario", "--sensor", "--delay", "--shaper", "--out", "1 ms", "exit status"):
        assert needle in text


def test_console_script_simulates(tmp_path):
    exe = shutil.which("flexarm")
    cmd = [exe] if exe else [sys.executable, "-m", "flexarm"]
    out_dir = tmp_path / "run"
    argv = ["simulate", "--duration", "0.2", "--json", "--out", str(out_dir)]
    ok = subprocess.run([*cmd, *argv], capture_output=True, text=True, check=False)
    assert ok.returncode == 0, ok.stderr
    assert strict_json(ok.stdout)["sim_time_s"] == pytest.approx(0.2)
    assert {p.name for p in out_dir.iterdir()} == FILES
