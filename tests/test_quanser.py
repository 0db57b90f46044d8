"""The Quanser 2 DOF Serial Flexible Link examples run as they are, on the rig's measured
files (``../shared/data/quanser_2dsfl``, or ``$FLEXARM_QUANSER``), and reach what the
example's README reports (regression bounds with a stated margin: a slip shows here)."""

from __future__ import annotations

import copy
import json
import os
import pathlib
import tomllib

import pytest

import flexarm as fa
from flexarm.calibration.config import CalibrationConfig
from helpers.cli import run_captured as run_cli

ROOT = pathlib.Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples" / "quanser_2dsfl"
DATA = pathlib.Path(
    os.environ.get("FLEXARM_QUANSER", ROOT.parent / "shared" / "data" / "quanser_2dsfl")
)

pytestmark = pytest.mark.skipif(
    not (DATA / "lqg_step_10deg_run01.mat").is_file(),
    reason=f"the Quanser rig's files are not in {DATA} (set FLEXARM_QUANSER to their directory)",
)

MARGIN = 2.0  # percentage points below what the example's README reports


@pytest.fixture(scope="module")
def stage1(tmp_path_factory):
    """The example run as a user runs it: ``flexarm calibrate ... --json --out DIR``
    (one calibration serves every test of its result)."""
    out = tmp_path_factory.mktemp("stage1") / "out"
    status, stdout, err = run_cli(
        "calibrate", EXAMPLES / "stage1_steps.toml", "--data", DATA, "--json", "--out", out
    )
    assert status == 0, err
    return json.loads(stdout), out


def test_stage1_fits_its_training_runs(stage1):
    """Reported: 78.7 % and 81.3 % (80 % on each is not reached: see the guide)."""
    summary, _ = stage1
    fits = [r["channels"]["th12"]["fit_percent"] for r in summary["training"]]
    assert len(fits) == 2 and min(fits) >= 78.7 - MARGIN and max(fits) >= 81.3 - MARGIN
    for r in summary["training"] + summary["validation"]:
        c = r["channels"]["th12"]
        assert c["fit_percent"] > c["fit_percent_initial"] + 20  # the calibration helped
    p = summary["parameters"]
    assert all(e["determined"] for e in p.values())
    assert 0.08 <= p["delay th12"]["value"] <= 0.16  # the logger's lag, about 0.1 s


def test_stage1_predicts_a_step_run_it_has_not_seen():
    """Fitted on one LQ step run, the other predicted (its initial states estimated,
    the parameters held): reported 78.3 % and 80.6 %, the 75 % asked for met."""
    data = tomllib.loads((EXAMPLES / "stage1_steps.toml").read_text())
    for held_out in (0, 1):
        d = copy.deepcopy(data)
        d["records"][held_out]["role"] = "validation"
        d["records"] = d["records"][:2]
        config = CalibrationConfig.from_dict(d, "loo", EXAMPLES).with_data(DATA)
        cal = fa.calibrate(config)
        unseen = next(r for r in cal.records if r.role == "validation")
        assert unseen.channels["th12"].fit_percent >= 75.0


def test_stage1_from_the_command_line(stage1):
    summary, out = stage1
    assert set(summary["parameters"]) == {"EI1", "J tip", "damping ratio", "delay th12"}
    for entry in summary["parameters"].values():
        assert {"value", "ci95"} <= set(entry)
    assert [r["file"] for r in summary["training"]] == [
        str(DATA / "lqg_step_10deg_run01.mat"),
        str(DATA / "lqg_step_neg_10deg_run01.mat"),
    ]
    assert all(
        "fit_percent" in c and "rms" in c
        for r in summary["validation"]
        for c in r["channels"].values()
    )
    written = {p.name for p in out.iterdir()}
    assert {"summary.json", "calibrated.toml", "report.html", "record0.png"} <= written


def test_the_current_driven_example_runs_as_it_is_on_a_short_window():
    """``fsf_current.toml`` reads its six files, builds its arm (rigid joints with their
    drives, two strips, stage 2's housing at strip 1's tip) and fits: here on 2 s of
    each part and three evaluations (the whole calibration is a command-line run of
    minutes; its figures are in the guide)."""
    data = tomllib.loads((EXAMPLES / "fsf_current.toml").read_text())
    data["calibration"].update(max_evaluations=3, segment=0.0, initial_state="measured")
    data["records"][0].update(start=1.1, stop=3.1)
    data["records"][1].update(start=10.0, stop=12.0)
    cal = fa.calibrate(CalibrationConfig.from_dict(data, "fsf", EXAMPLES).with_data(DATA))
    assert [r.role for r in cal.records] == ["training", "validation"]
    for r in cal.records:
        assert set(r.channels) == {"th11", "th21", "th12", "th22"}
        assert len(r.t) == 1000  # 2 s at the logger's 500 Hz
    p = cal.parameters()
    assert set(p) == {
        *("B11", "B21", "Fc1", "Fc2", "Kt2 factor", "EI1", "EI2", "zeta1", "zeta2"),
        *("delay th12", "delay th22"),
    }
    # the logger's strain channels lag its encoders by about 0.1 s
    assert 0.02 <= p["delay th12"]["value"] <= 0.3 and 0.02 <= p["delay th22"]["value"] <= 0.3
    train = cal.records[0].channels.values()
    assert sum(c.fit_percent for c in train) >= sum(c.fit_percent_initial for c in train)
