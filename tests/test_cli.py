"""The ``flexarm`` command line: output, JSON, and one-line errors with status 2."""

from __future__ import annotations

import json
import shutil
import subprocess
import sys

import pytest

from flexarm.cli import build_parser
from helpers.cli import error_line, help_text, run

COMMANDS = ("reproduce", "simulate", "sweep", "identify", "calibrate", "modes")  # the API contract


def test_help_lists_every_command(capsys):
    status, _, _ = run(capsys)
    assert status == 0
    listing = help_text(capsys)
    rows = [line.split() for line in listing.splitlines()]
    for name in COMMANDS:  # each starts a line of the listing
        assert any(row[:1] == [name] for row in rows), name
    sub = next(a for a in build_parser()._actions if a.dest == "command")
    assert set(sub.choices) == set(COMMANDS)  # nothing registered that the help omits
    helps = {a.dest: a.help for a in sub._choices_actions}
    flat = " ".join(listing.split())
    assert all(helps[name] and " ".join(helps[name].split()) in flat for name in COMMANDS)


@pytest.mark.parametrize("name", COMMANDS)
def test_every_command_has_help(capsys, name):
    assert help_text(capsys, name).startswith(f"usage: flexarm {name}")


def test_modes_help(capsys):
    assert "--length" in help_text(capsys, "modes")


def test_modes_prints_the_paper_arm(capsys):
    status, out, err = run(capsys, "modes")
    assert status == 0 and err == ""
    assert "1.8751040687" in out
    assert "12.28119" in out  # rad/s
    assert "1.95461" in out  # Hz
    assert out.count("Link") == 2


def test_modes_json_for_the_paper_arm(capsys):
    status, out, _ = run(capsys, "modes", "--json", "--n-modes", "3")
    assert status == 0
    data = json.loads(out)
    assert len(data["links"]) == 2
    link = data["links"][0]
    assert link["roots"][:3] == pytest.approx([1.8751040687, 4.6940911330, 7.8547574382], abs=1e-10)
    assert link["frequencies_rad_s"][0] == pytest.approx(12.281, abs=5e-4)
    assert link["frequencies_hz"][0] == pytest.approx(12.281 / (2 * 3.141592653589793), rel=1e-4)
    assert data["arm_frequencies_locked_rad_s"][0] > 0


@pytest.mark.parametrize("joints", ["linear", "nonlinear"])
def test_modes_reports_linearised_frequencies_with_joints(capsys, joints):
    status, out, _ = run(capsys, "modes", "--joints", joints, "--json")
    assert status == 0
    data = json.loads(out)
    assert data["joints"] == joints
    rigid = json.loads(run(capsys, "modes", "--json")[1])
    # two more elastic degrees of freedom (the joint springs), and a softer arm
    assert (
        len(data["arm_frequencies_locked_rad_s"]) == len(rigid["arm_frequencies_locked_rad_s"]) + 2
    )
    assert data["arm_frequencies_locked_rad_s"][0] < rigid["arm_frequencies_locked_rad_s"][0]
    status, out, _ = run(capsys, "modes", "--joints", joints)
    assert "joints" in out


#: A unit link given on the command line (length, flexural rigidity, linear density).
UNIT_LINK = ("--length", "1", "--flexural-rigidity", "1", "--linear-density", "1")


def test_modes_for_a_link_on_the_command_line(capsys):
    argv = ("modes", *UNIT_LINK, "--tip-mass", "1", "--n-modes", "2", "--json")
    status, out, _ = run(capsys, *argv)
    assert status == 0
    roots = json.loads(out)["links"][0]["roots"]
    assert roots[0] == pytest.approx(1.24792, abs=1e-5)  # tip-mass ratio 1 (Blevins)


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (
            ["modes", "--length", "-1", "--flexural-rigidity", "1", "--linear-density", "1"],
            "length",
        ),
        (
            ["modes", "--length", "nan", "--flexural-rigidity", "1", "--linear-density", "1"],
            "length",
        ),
        (["modes", "--length", "1"], "--flexural-rigidity"),
        (["modes", "--n-modes", "-2"], "--n-modes"),
        (["modes", "--n-modes", "x"], "--n-modes"),
        (["modes", "--boundary", "pinned"], "--boundary"),
        (["modes", "--normalization", "unit"], "--normalization"),
        (["modes", "--tip-mass", "1"], "--tip-mass"),
        (["modes", "--joints", "elastic"], "--joints"),
        (["modes", *UNIT_LINK, "--joints", "linear"], "--joints"),
        (["modes", "--bogus"], "--bogus"),
        (["nonsense"], "nonsense"),
    ],
)
def test_bad_input_is_one_line_with_status_2(capsys, argv, needle):
    status, out, err = run(capsys, *argv)
    assert status == 2
    assert out == ""
    assert needle in error_line(err)


def test_console_script_runs_without_traceback():
    exe = shutil.which("flexarm")
    cmd = [exe] if exe else [sys.executable, "-m", "flexarm"]
    ok = subprocess.run([*cmd, "modes", "--json"], capture_output=True, text=True, check=False)
    assert ok.returncode == 0, ok.stderr
    assert json.loads(ok.stdout)["links"][0]["roots"][0] == pytest.approx(1.8751040687)
    bad = subprocess.run(
        [*cmd, "modes", "--n-modes", "-1"], capture_output=True, text=True, check=False
    )
    assert bad.returncode == 2
    assert len(bad.stderr.strip().splitlines()) == 1 and "Traceback" not in bad.stderr
