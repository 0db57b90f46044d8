"""``flexarm reproduce`` on a short horizon: every promised artefact, the claims,
neutral adaptation equal to the nonadaptive runs, figures with units, bad options;
and the verdict logic on hand-made case lists, expected verdicts written from the
stated rule."""

from __future__ import annotations

import csv
import json
import re
import subprocess
import sys

import numpy as np
import pytest

from flexarm.studies.reproduction import OUTPUT_FILES, SENSOR_CASES, RunMatrix, reproduce
from flexarm.studies.reproduction.cases import Case, CaseResult
from flexarm.studies.reproduction.verdicts import Part, claims, judge, tracks_well
from helpers.cli import error_line, run

SHORT = ("--duration", "0.15", "--ks-range", "0,10", "--workers", "2", "--no-beyond")


@pytest.fixture(scope="module")
def study():
    return reproduce(
        duration=0.15,
        ks_range=(0.0, 10.0),
        laws=("scaled", "damping"),
        workers=2,
        progress=False,
        beyond=False,
    )


def test_matrix_is_models_by_controllers_by_sensors(study):
    got = [(c.case.sensor_model, c.case.controller, c.case.sensor) for c in study.cases]
    expected = [
        (m, c, s) for m in ("paper", "physical") for c in ("pd", "fuzzy") for s in SENSOR_CASES
    ]
    assert got == expected
    assert len(study.delay_study) == 3 * 6  # the paper's model under each delay
    assert {c.case.sensor_model for c in study.delay_study} == {"paper"}
    assert len(study.ks_study) == 2 * 2 * 2 * 3  # models, ks, laws, sensors


def test_the_paper_model_runs_through_the_seed_delay_with_the_reference_delayed(study):
    paper = [c for c in study.cases if c.case.sensor_model == "paper" and c.case.sensor != "joint"]
    for c in paper:
        assert c.case.delay == "seed" and c.delay_s > 0
        assert c.result.info["delay_method"] == "pade" and c.result.info["delay_reference"]
        assert c.result.info["sensor"].endswith("(paper model)")
    physical = [c for c in study.cases if c.case.sensor_model == "physical"]
    assert all(c.delay_s == 0.0 for c in physical)


def test_neutral_fuzzy_runs_equal_the_nonadaptive_runs(study):
    pd = {(c.case.sensor, c.case.sensor_model): c for c in study.cases if c.case.controller == "pd"}
    for c in study.ks_study:
        if c.case.ks != 0.0:
            continue
        ref = pd[(c.case.sensor, c.case.sensor_model)]
        assert c.status == ref.status
        np.testing.assert_allclose(c.result.q, ref.result.q, rtol=1e-10, atol=1e-12)


def test_delay_models_give_the_travel_delays(study):
    by = {(c.case.sensor, c.case.delay): c.delay_s for c in study.delay_study}
    assert by[("joint", "seed")] == 0.0  # collocated: no travel path
    assert by[("tip", "none")] == 0.0
    assert by[("tip", "seed")] == pytest.approx(9.0 / 41783.0, rel=1e-3)
    assert by[("tip", "dispersive")] > by[("tip", "seed")]  # bending waves are slower


def test_shared_runs_are_run_once(study):
    # the matrix: 6 runs with the paper's model, 4 more with the physical one (the
    # encoders are the same); the delay study: "seed" is the matrix, "none" and
    # "dispersive" add the 4 noncollocated runs each; the ks study (ks 0 and 10, two
    # laws): 4 settings with the encoders (shared by the models) and 4 settings x 2
    # noncollocated sensors x 2 models; the matrix again on the converged arm (6 + 4)
    assert study.settings["runs"] == (6 + 4) + (4 + 4) + (4 + 16) + (6 + 4)


def test_run_matrix_lists_and_deduplicates():
    runs = RunMatrix.build(
        ks=1.0, law="scaled", ks_range=(0.0, 1.0), laws=("scaled",), delays=("none", "seed")
    )
    assert (len(runs.matrix), len(runs.delay_study), len(runs.ks_study)) == (12, 12, 12)
    # the matrix: 6 + 4 (the encoders' runs are shared by the models); the delay
    # study adds the 4 noncollocated runs without delay ("seed" is the matrix); the ks
    # study adds ks = 0: 1 with the encoders + 2 noncollocated x 2 models (ks = 1 scaled
    # is the matrix)
    assert len(runs.unique()) == 10 + 4 + 5
    assert Case("pd", "tip", ks=0.0, law="damping").key() == Case("pd", "tip").key()
    assert Case("fuzzy", "tip", ks=0.0).key() != Case("fuzzy", "tip").key()
    assert Case("pd", "joint", sensor_model="physical").key() == Case("pd", "joint", "seed").key()
    assert Case("pd", "tip", sensor_model="physical").key() != Case("pd", "tip").key()
    assert set(RunMatrix.build(ks=1.0, law="scaled").unique()) == {c.key() for c in runs.matrix}


def test_claims_state_a_verdict_with_numbers(study):
    assert len(study.claims) == 2 * 4  # per sensor model
    assert [c["sensor_model"] for c in study.claims] == ["paper"] * 4 + ["physical"] * 4
    for claim in study.claims:
        assert claim["verdict"] in {"supported", "partly supported", "not supported"}
        assert re.search(r"\d", claim["evidence"])


def test_write_produces_every_artefact_at_once(study, tmp_path):
    out = tmp_path / "rep"
    files = study.write(out)
    assert sorted(files) == sorted(OUTPUT_FILES)
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES)
    summary = json.loads((out / "summary.json").read_text())
    assert {"cases", "claims", "sensitivity", "settings"} <= set(summary)
    rows = list(csv.DictReader((out / "table.csv").open()))
    assert len(rows) == 12 + 18 + 24  # the matrix (two models), the delay and ks studies
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
    assert len(data["cases"]) == 12
    for case in data["cases"]:
        assert {
            "controller",
            "sensor",
            "sensor_model",
            "status",
            "rms_error_m",
            "max_error_m",
        } <= set(case)
        assert (case["rms_error_m"] is None) == (case["status"] == "diverged")
    assert data["claims"] and all("verdict" in c for c in data["claims"])
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES)


def test_cli_text_summary(capsys, tmp_path):
    status, stdout, err = run(capsys, "reproduce", *SHORT, "--out", tmp_path / "r")
    assert status == 0, err
    assert "claims (" in stdout and "report.html" in stdout


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
        (("--dt", "1e-9", "--duration", "1", "--no-sensitivity"), "FLEXARM_MAX_MEMORY"),
        (("--duration", "1e9", "--no-sensitivity"), "FLEXARM_MAX_MEMORY"),
    ],
)
def test_cli_bad_options_are_one_line_and_write_nothing(capsys, tmp_path, argv, match):
    out = tmp_path / "r"
    status, _, err = run(capsys, "reproduce", "--out", out, *argv)
    assert status == 2
    assert match in error_line(err)
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


@pytest.mark.parametrize("switch", ["sensitivity", "beyond", "converged"])
@pytest.mark.parametrize("value", [1, "no", None, np.True_])
def test_every_switch_of_the_study_must_be_a_bool(switch, value):
    with pytest.raises(TypeError, match=f"'{switch}' parameter of reproduce must be a bool"):
        reproduce(duration=0.01, **{switch: value})


# ---------------------------------------------------------------- figures
UNIT_LABEL = re.compile(r"^\S.* \([^()]+\)$")  # "quantity (unit)"


def assert_labels_have_units(fig):
    for ax in fig.axes:
        for label in (ax.get_xlabel(), ax.get_ylabel()):
            assert label == "" or UNIT_LABEL.match(label), label


def test_figures_draw_on_new_or_given_figures_with_units(study):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.figure import Figure

    for name, panels in (("plot_tracking", 12), ("plot_deflections", 12), ("plot_sensitivity", 3)):
        fig = getattr(study, name)()
        assert isinstance(fig, Figure) and len(fig.axes) == panels
        assert all(ax.get_xlabel() for ax in fig.axes)
        assert_labels_have_units(fig)
        given = Figure()
        assert getattr(study, name)(given) is given and len(given.axes) == panels
    assert study.plot_tracking().axes[0].get_xlabel() == "x (m)"
    assert study.plot_deflections().axes[0].get_ylabel() == "tip deflection (mm)"
    assert study.plot_sensitivity().axes[0].get_ylabel() == "RMS error (mm)"
    ax, artist = study.plot_surface()
    assert ax.name == "3d" and artist is not None
    assert (ax.get_xlabel(), ax.get_ylabel(), ax.get_zlabel()) == ("δ1 (m)", "δ2 (m)", "λ (-)")
    plt.close("all")


def test_the_text_summary_lists_the_matrix_and_the_verdicts(study):
    text = study.text()
    assert text.startswith(f"{study.settings['runs']} runs in ")
    assert len([ln for ln in text.splitlines() if ln.startswith("  pd ")]) == 6
    for claim in study.claims:
        assert f"{claim['claim']}: {claim['verdict'].upper()}" in text


# ------------------------------------------------------------ light imports
def test_the_command_line_and_the_report_load_no_simulator():
    """`flexarm reproduce --help` and the verdicts/report modules need no Numba or Matplotlib."""
    code = """
import importlib.util, sys, types
spec = importlib.util.find_spec("flexarm.cli")  # imports flexarm (light), not flexarm.cli
pkg = types.ModuleType("flexarm.cli")
pkg.__path__ = list(spec.submodule_search_locations)
sys.modules["flexarm.cli"] = pkg  # skip the other commands' imports
import flexarm.cli._common as common
import flexarm.cli.reproduce as cli
import flexarm.studies.reproduction as rep
import flexarm.studies.reproduction.report, flexarm.studies.reproduction.verdicts
parser = common.Parser(prog="flexarm")
cli.add_parser(parser.add_subparsers())
assert parser.parse_args(["reproduce", "--law", "damping"]).law == "damping"
assert rep.OUTPUT_FILES and rep.SENSOR_CASES
heavy = [m for m in sys.modules if m.split(".")[0] in ("numba", "matplotlib")
         or m in ("flexarm.sim.closed_loop", "flexarm.studies.reproduction.experiment")]
assert not heavy, heavy
"""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert res.returncode == 0, res.stderr


def test_every_adaptation_law_named_light_is_one_the_controller_takes():
    """The names the command line reads without compiling a law are the ones the
    fuzzy law accepts (and it refuses another)."""
    from flexarm.control.adaptive import FuzzyAdaptiveJTPD
    from flexarm.studies.reproduction import cases

    for law in cases.ADAPTATION_LAWS:
        assert FuzzyAdaptiveJTPD(150.0, 17.0, law=law).law == law
    with pytest.raises(ValueError, match="'law'"):
        FuzzyAdaptiveJTPD(150.0, 17.0, law="gain")


# ------------------------------------------------- verdicts on hand-made cases
# The stated rule: a run tracks well when it completes (no divergence) and its RMS
# error is <= the tolerance; a claim is made of parts, each holding when it holds for
# every run it is about; "supported" when every part holds, "not supported" when none
# does, "partly supported" when some parts hold (only claim 1 has two parts:
# collocated and noncollocated).
TOL = 0.2  # m
DIVERGED = None


def outcome(controller, sensor, rms, *, ks=1.0, law="scaled"):
    """A case result built by hand; ``rms=DIVERGED`` is a run that diverged at 0.01 s."""
    case = Case(controller, sensor, ks=ks, law=law)
    if rms is DIVERGED:
        metrics = {"sim_time_s": 0.01, "wall_time_s": 0.0}
        return CaseResult(case, "diverged", 0.01, metrics, 0.0, 5.0, result=None)
    metrics = {"rms_error_m": rms, "max_error_m": 2 * rms}
    return CaseResult(case, "ok", None, metrics, 0.0, -5.0, result=None)


def matrix(pd, fuzzy):
    """The paper's matrix from RMS errors per sensor (joint, tip, elbow), pd then fuzzy."""
    return [outcome("pd", s, r) for s, r in zip(SENSOR_CASES, pd, strict=True)] + [
        outcome("fuzzy", s, r) for s, r in zip(SENSOR_CASES, fuzzy, strict=True)
    ]


@pytest.mark.parametrize(
    ("holds", "expected"),
    [
        ((True, True), "supported"),
        ((False, False), "not supported"),
        ((True, False), "partly supported"),
        ((True,), "supported"),
        ((False,), "not supported"),  # a one-part claim is never partly supported
    ],
)
def test_judging_parts(holds, expected):
    assert (
        judge([Part(name=f"part {i}", holds=h, evidence="") for i, h in enumerate(holds)])
        == expected
    )


def test_tracking_well_needs_completion_and_the_tolerance():
    assert tracks_well(outcome("pd", "joint", 0.2), TOL)  # at the tolerance: tracks well
    assert not tracks_well(outcome("pd", "joint", 0.2000001), TOL)
    assert not tracks_well(outcome("pd", "joint", DIVERGED), TOL)
    # a diverged run is poor whatever error it recorded before blowing up
    blown = outcome("pd", "joint", DIVERGED)
    blown.metrics["rms_error_m"] = 0.01
    assert not tracks_well(blown, TOL)


@pytest.mark.parametrize(
    ("pd", "fuzzy", "expected"),
    [
        # pd: joint at the tolerance tracks well, tip just above and elbow diverged are
        # poor (2 of 3 poor); fuzzy tracks well everywhere and beats pd everywhere
        (
            (0.2, 0.2000001, DIVERGED),
            (0.1, 0.2, 0.19),
            ("partly supported", "supported", "supported"),
        ),
        # everything diverges: pd poor everywhere; fuzzy never tracks; inf vs inf is no gain
        (
            (DIVERGED, DIVERGED, DIVERGED),
            (DIVERGED, DIVERGED, DIVERGED),
            ("supported", "not supported", "not supported"),
        ),
        # pd tracks everywhere; fuzzy: equal at the joint (no gain), better at the tip,
        # diverged at the elbow: a claim about every sensor fails with one of them
        (
            (0.05, 0.05, 0.05),
            (0.05, 0.01, DIVERGED),
            ("not supported", "not supported", "not supported"),
        ),
        # fuzzy completes where pd diverges, but above the tolerance: better, not good
        (
            (DIVERGED, DIVERGED, DIVERGED),
            (0.5, 0.5, 0.5),
            ("supported", "not supported", "supported"),
        ),
    ],
)
def test_matrix_claims_follow_the_stated_rule(pd, fuzzy, expected):
    got = claims(matrix(pd, fuzzy), [], TOL)
    assert len(got) == 3  # no ks study, no fourth claim
    assert [c["verdict"] for c in got] == list(expected)
    assert got[0]["claim"].startswith("Nonadaptive control tracks poorly")
    assert got[1]["claim"].startswith("Fuzzy adaptive control tracks well")
    assert got[2]["claim"].startswith("Fuzzy adaptation improves")


def test_claim_evidence_gives_the_numbers():
    got = claims(matrix((0.2, 0.2000001, DIVERGED), (0.05, 0.3, DIVERGED)), [], TOL)
    pd, fz, gain = (c["evidence"] for c in got)
    assert "joint: RMS 200 mm" in pd and "end effector: RMS 200 mm" in pd
    assert "0.5 m from elbow: diverged at t = 0.01 s" in pd
    assert "RMS <= 200 mm" in pd and "RMS <= 200 mm" in fz
    assert "rad/s" in pd  # the linearised poles
    # fuzzy is lower at the joint only (0.3 > 0.2000001; both diverged at the elbow)
    assert gain.startswith("sensors where the adaptive RMS error is lower: joint (")
    assert "0.5 m from elbow: inf vs inf mm" in gain


def test_ks_claim_needs_one_good_setting_per_sensor():
    base = matrix((0.1, DIVERGED, DIVERGED), (0.1, DIVERGED, DIVERGED))

    def ks_runs(per_sensor):
        return [
            outcome("fuzzy", s, rms, ks=ks, law=law)
            for s, runs in zip(SENSOR_CASES, per_sensor, strict=True)
            for ks, law, rms in runs
        ]

    # joint: one good setting; tip: all diverged; elbow: completes, never within 0.2 m
    study = ks_runs(
        [
            [(0.0, "scaled", 0.5), (10.0, "damping", 0.1)],
            [(0.0, "scaled", DIVERGED), (10.0, "damping", DIVERGED)],
            [(0.0, "scaled", 0.3), (10.0, "damping", 0.25)],
        ]
    )
    got = claims(base, study, TOL)
    assert len(got) == 4 and got[3]["claim"].startswith("Some setting of the fuzzy law")
    assert got[3]["verdict"] == "not supported"  # good with the joint sensor only
    evidence = got[3]["evidence"]
    assert "joint: RMS 100 mm at ks = 10 (damping)" in evidence  # the best setting
    assert "end effector: every setting diverged" in evidence
    assert "0.5 m from elbow: RMS 250 mm at ks = 10 (damping)" in evidence

    good = ks_runs([[(1.0, "scaled", 0.2)], [(1.0, "scaled", 0.15)], [(1.0, "scaled", 0.0)]])
    assert claims(base, good, TOL)[3]["verdict"] == "supported"
    bad = ks_runs([[(1.0, "scaled", 0.21)], [(1.0, "scaled", DIVERGED)], [(1.0, "scaled", 1.0)]])
    assert claims(base, bad, TOL)[3]["verdict"] == "not supported"
    # every sensor has a good setting, but not the same one: no setting for all
    apart = ks_runs(
        [
            [(1.0, "scaled", 0.1), (10.0, "scaled", 0.5)],
            [(1.0, "scaled", 0.5), (10.0, "scaled", 0.1)],
            [(1.0, "scaled", 0.1), (10.0, "scaled", 0.1)],
        ]
    )
    assert claims(base, apart, TOL)[3]["verdict"] == "not supported"


def test_claims_are_judged_per_sensor_model():
    paper = matrix((0.1, 0.1, 0.1), (0.1, 0.1, 0.1))
    physical = [
        outcome(c, s, r)
        for c, rs in (("pd", (0.1, DIVERGED, DIVERGED)), ("fuzzy", (0.1, DIVERGED, DIVERGED)))
        for s, r in zip(SENSOR_CASES, rs, strict=True)
    ]
    for c in physical:
        object.__setattr__(
            c, "case", Case(c.case.controller, c.case.sensor, sensor_model="physical")
        )
    got = claims(paper + physical, [], TOL)
    assert [(c["sensor_model"], c["verdict"]) for c in got] == [
        ("paper", "not supported"),  # nonadaptive tracks well everywhere
        ("paper", "supported"),
        ("paper", "not supported"),  # equal errors are no improvement
        ("physical", "partly supported"),  # poor with the distant sensors, not the joint
        ("physical", "not supported"),
        ("physical", "not supported"),
    ]


def test_fuzzy_surface_labels_can_be_given_and_are_checked():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from flexarm.fuzzy import paper_system, plot_surface

    _, ax = plt.subplots()
    plot_surface(paper_system(), ax=ax, n=5, labels=("a (m)", "b (m)", "c (-)"))
    assert (ax.get_xlabel(), ax.get_ylabel()) == ("a (m)", "b (m)")
    with pytest.raises(TypeError, match="'labels' parameter of plot_surface"):
        plot_surface(paper_system(), ax=ax, n=5, labels=("x", "y"))
    plt.close("all")


# ------------------------------------------------------------------ the converged arm
def test_the_matrix_runs_again_on_a_converged_arm(study):
    """Same cases on three clamped-mass modes per link with stiffening, at the
    converged arm's own period, judged by the same rule."""
    conv = study.converged
    assert conv is not None
    assert [(c.case.sensor_model, c.case.controller, c.case.sensor) for c in conv.cases] == [
        (c.case.sensor_model, c.case.controller, c.case.sensor) for c in study.cases
    ]
    for c in conv.cases:
        assert c.case.arm == "converged" and c.result.info["n_modes"] == [3, 3]
        assert c.result.info["dt_s"] == conv.dt_s
    assert {c["claim"] for c in conv.claims} == {c["claim"] for c in study.claims[:3]} | {
        c["claim"] for c in study.claims if c["sensor_model"] == "physical"
    } - {c["claim"] for c in study.claims if "setting" in c["claim"]}
    summary = study.summary()["converged"]
    assert summary["arm"]["geometric_stiffening"] is True and summary["dt_s"] == conv.dt_s


def test_the_converged_period_follows_its_rule():
    """Half the zero-order-hold bound at the worst corner, a 1-2-5 number, never longer
    than the study's period: the sampled loop is stable at every corner."""
    from flexarm import FlexibleArm
    from flexarm.control.controllers import JacobianTransposePD
    from flexarm.control.sampling import check_sampling
    from flexarm.control.signals import r_position, reference_size
    from flexarm.control.trajectories import Square
    from flexarm.sensing.sensors import JointSensor
    from flexarm.studies.reproduction.converged import converged_period

    dt = converged_period(2e-4)
    mantissa = dt / 10 ** np.floor(np.log10(dt))
    assert min(abs(mantissa - m) for m in (1.0, 2.0, 5.0)) < 1e-9
    assert converged_period(dt / 2) == dt / 2
    arm = FlexibleArm.paper(n_modes=3, boundary="clamped-mass", geometric_stiffening=True)
    law = JacobianTransposePD.from_arm(arm)
    for corner in Square().corners:
        theta = arm.inverse_kinematics(corner)
        r = np.zeros(reference_size(2))
        r[r_position(2) : r_position(2) + 2] = corner  # at rest on the corner
        params = law.parameters(arm)
        for period in (dt, 2 * dt):
            verdict = check_sampling(arm, law, JointSensor(), theta, r, params, np.zeros(0), period)
            assert verdict.spectral_radius <= 1.0 + 1e-9


def test_verdict_changes_are_named():
    from flexarm.studies.reproduction.converged import verdict_changes

    def claim(name, model, verdict):
        return {"claim": name, "sensor_model": model, "verdict": verdict, "evidence": ""}

    paper = [claim("A", "paper", "supported"), claim("B", "paper", "not supported")]
    converged = [claim("A", "paper", "partly supported"), claim("B", "paper", "not supported")]
    (change,) = verdict_changes(paper, converged)
    assert change.startswith("A [paper sensor model]: supported") and "partly" in change
