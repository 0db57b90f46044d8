"""``flexarm reproduce`` on a short horizon: every promised artefact, the claims,
neutral adaptation equal to the nonadaptive runs, and bad options."""

from __future__ import annotations

import csv
import json
import re

import numpy as np
import pytest

from flexarm.cli import main
from flexarm.studies.reproduction import OUTPUT_FILES, SENSOR_CASES, reproduce

SHORT = ("--duration", "0.15", "--ks-range", "0,10", "--workers", "2")


def run(capsys, *argv):
    status = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


@pytest.fixture(scope="module")
def study():
    return reproduce(
        duration=0.15, ks_range=(0.0, 10.0), laws=("scaled", "damping"), workers=2, progress=False
    )


def test_matrix_is_controllers_by_sensors(study):
    got = [(c.case.controller, c.case.sensor) for c in study.cases]
    assert got == [(c, s) for c in ("pd", "fuzzy") for s in SENSOR_CASES]
    assert len(study.delay_study) == 3 * 6
    assert len(study.ks_study) == 2 * 2 * 3


def test_neutral_fuzzy_runs_equal_the_nonadaptive_runs(study):
    pd = {c.case.sensor: c for c in study.cases if c.case.controller == "pd"}
    for c in study.ks_study:
        if c.case.ks != 0.0:
            continue
        ref = pd[c.case.sensor]
        assert c.status == ref.status
        np.testing.assert_allclose(c.result.q, ref.result.q, rtol=1e-10, atol=1e-12)


def test_delay_models_give_the_travel_delays(study):
    by = {(c.case.sensor, c.case.delay): c.delay_s for c in study.delay_study}
    assert by[("joint", "seed")] == 0.0  # collocated: no travel path
    assert by[("tip", "none")] == 0.0
    assert by[("tip", "seed")] == pytest.approx(9.0 / 41783.0, rel=1e-3)
    assert by[("tip", "dispersive")] > by[("tip", "seed")]  # bending waves are slower


def test_claims_state_a_verdict_with_numbers(study):
    assert len(study.claims) == 4
    for claim in study.claims:
        assert claim["verdict"] in {"supported", "partly supported", "not supported"}
        assert re.search(r"\d", claim["evidence"])


def test_claim_verdicts_follow_the_stated_tolerance(study):
    tol = study.settings["tolerance_m"]
    fuzzy = [c for c in study.cases if c.case.controller == "fuzzy"]
    good = sum(c.status == "ok" and c.rms <= tol for c in fuzzy)
    expected = {3: "supported", 0: "not supported"}.get(good, "partly supported")
    assert study.claims[1]["verdict"] == expected


def test_write_produces_every_artefact_at_once(study, tmp_path):
    out = tmp_path / "rep"
    files = study.write(out)
    assert sorted(files) == sorted(OUTPUT_FILES)
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES)
    summary = json.loads((out / "summary.json").read_text())
    assert {"cases", "claims", "sensitivity", "settings"} <= set(summary)
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert len(rows) == 6 + 18 + 12
    page = (out / "report.html").read_text()
    assert page.count("data:image/png;base64,") == 4
    assert not re.search(r"src=['\"](?!data:)", page)  # self-contained
    for name in OUTPUT_FILES:
        if name.endswith(".png"):
            assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_json_summary(capsys, tmp_path):
    out = tmp_path / "results"
    status, stdout, err = run(
        capsys, "reproduce", *SHORT, "--no-sensitivity", "--out", out, "--json"
    )
    assert status == 0, err
    data = json.loads(stdout)
    assert len(data["cases"]) == 6
    for case in data["cases"]:
        assert {"controller", "sensor", "rms_error_m", "max_error_m"} <= set(case)
    assert data["claims"] and all("verdict" in c for c in data["claims"])
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES)


def test_cli_text_summary(capsys, tmp_path):
    status, stdout, err = run(capsys, "reproduce", *SHORT, "--out", tmp_path / "r")
    assert status == 0, err
    assert "claims:" in stdout and "report.html" in stdout


@pytest.mark.parametrize(
    ("argv", "match"),
    [
        (("--ks", "-1"), "ks"),
        (("--ks-range", "1,x"), "--ks-range"),
        (("--ks-range", "1,-2"), "--ks-range"),
        (("--law", "magic"), "--law"),
        (("--duration", "-1"), "duration"),
        (("--dt", "0"), "dt"),
        (("--tolerance", "nan"), "tolerance"),
        (("--workers", "0"), "workers"),
        (("--bogus",), "unrecognized"),
    ],
)
def test_cli_bad_options_are_one_line_and_write_nothing(capsys, tmp_path, argv, match):
    out = tmp_path / "r"
    status, _, err = run(capsys, "reproduce", "--out", out, *argv)
    assert status == 2
    assert match in err and len(err.strip().splitlines()) == 1
    assert "Traceback" not in err
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_cli_refuses_a_non_empty_out(capsys, tmp_path):
    (tmp_path / "keep.txt").write_text("mine")
    status, _, err = run(capsys, "reproduce", *SHORT, "--out", tmp_path)
    assert status == 2 and "not an empty directory" in err
    assert [p.name for p in tmp_path.iterdir()] == ["keep.txt"]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"laws": ("scaled", "magic")}, "'laws'"),
        ({"delays": ("pade",)}, "'delays'"),
        ({"ks_range": ()}, "non-empty"),
        ({"ks_range": (1.0, -1.0)}, "'ks_range'"),
    ],
)
def test_bad_study_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        reproduce(duration=0.01, **kwargs)
