"""Calibration against records simulated with known parameters: values recovered with
their confidence intervals, delays estimated, undetermined parameters refused, intervals
that cover the truth at their stated rate, bad configurations named by key."""

from __future__ import annotations

import copy

import numpy as np
import pytest

import flexarm as fa
from flexarm.calibration.config import CalibrationConfig
from flexarm.calibration.fit import load_records
from flexarm.calibration.model import Predictor, build_plant
from flexarm.errors import CalibrationError
from flexarm.model.drives import Drive
from flexarm.sensing.instruments import Encoder, JointDeflection, StrainGauge, delayed
from helpers.arms import two_rigid_rods_mass_matrix

FS = 250.0  # Hz


def _hub(t):
    """A smooth 0.3 rad step over 0.5 s (zero rate and acceleration at both ends)."""
    s = np.clip(t / 0.5, 0.0, 1.0)
    return 0.3 * (10 * s**3 - 15 * s**4 + 6 * s**5)


def _hub_motion(t):
    """The step's angle, rate and acceleration (the exact motion, shape (m, 1) each)."""
    s = np.clip(t / 0.5, 0.0, 1.0)
    inside = (t > 0) & (t < 0.5)
    rate = np.where(inside, 0.3 / 0.5 * (30 * s**2 - 60 * s**3 + 30 * s**4), 0.0)
    acc = np.where(inside, 0.3 / 0.25 * (60 * s - 180 * s**2 + 120 * s**3), 0.0)
    return _hub(t)[:, None], rate[:, None], acc[:, None]


def _beam(ei=2.0, zeta=0.03):
    return fa.FlexibleArm(
        [fa.Link(0.3, ei, 0.8, n_modes=2, modal_damping=zeta)],
        payload_mass=0.5,
        payload_inertia=0.01,
        geometric_stiffening=False,
    )


BEAM_ARM = {
    "geometric_stiffening": False,
    "payload_mass": 0.5,
    "payload_inertia": 0.01,
    "links": [
        {
            "length": 0.3,
            "flexural_rigidity": 1.4,
            "linear_density": 0.8,
            "n_modes": 2,
            "modal_damping": 0.01,
        }
    ],
}
GAUGE = {"kind": "strain_gauge", "link": 0, "thickness": 1e-3, "form": "tip_angle"}


def _beam_record(
    path, *, ei=2.0, zeta=0.03, delay=0.04, noise=0.01, seed=0, duration=2.0, offset=0.0
):
    """An .npz record of the beam: hub angle prescribed, the gauge's tip angle delayed,
    with white noise of ``noise`` times its standard deviation and ``offset`` times
    that deviation added as the gauge's zero."""
    t = np.arange(round(duration * FS) + 1) / FS
    arm = _beam(ei, zeta)
    run = fa.simulate_prescribed(arm, t, _hub_motion, substeps=4)
    y = delayed(t, StrainGauge(0, 0.0, 1e-3, "tip_angle").raw(arm, run.q), delay)
    rng = np.random.default_rng(seed)
    y = y + noise * np.std(y) * rng.standard_normal(y.shape) + offset * np.std(y)
    np.savez(path, time=t, theta=_hub(t), y=y)
    return path


def _beam_config(tmp_path, files, parameters, **settings):
    data = {
        "calibration": {"data": ".", "substeps": 4, "smoothing": 1e-9, **settings},
        "arm": copy.deepcopy(BEAM_ARM),
        "outputs": {"tip": {**GAUGE, "delay": "estimate"}},
        "parameters": parameters,
        "records": [
            {
                "file": f.name,
                "time": {"variable": "time", "unit": "s"},
                "inputs": [{"joint": 0, "kind": "angle", "variable": "theta", "unit": "rad"}],
                "outputs": {"tip": {"variable": "y", "unit": "rad"}},
            }
            for f in files
        ],
    }
    return CalibrationConfig.from_dict(data, "test.toml", tmp_path)


EI_AND_DAMPING = [
    {"name": "EI", "key": "arm.links[0].flexural_rigidity", "bounds": [0.5, 5.0]},
    {"name": "zeta", "key": "arm.links[0].modal_damping", "bounds": [0.0, 0.2]},
]


def test_a_beam_and_a_delay_are_recovered_from_a_noisy_prescribed_run(tmp_path):
    path = _beam_record(tmp_path / "run.npz")
    cal = fa.calibrate(_beam_config(tmp_path, [path], EI_AND_DAMPING))
    p = cal.parameters()
    assert p["EI"]["value"] == pytest.approx(2.0, rel=0.01)
    assert p["zeta"]["value"] == pytest.approx(0.03, rel=0.05)
    assert p["delay tip"]["value"] == pytest.approx(0.04, abs=2e-3)
    for name, truth in (("EI", 2.0), ("zeta", 0.03), ("delay tip", 0.04)):
        assert abs(p[name]["value"] - truth) <= 3 * p[name]["ci95"], name
        assert p[name]["determined"] is True
    fit = cal.records[0].channels["tip"]
    assert fit.fit_percent > 95 and fit.fit_percent > fit.fit_percent_initial + 20
    # the noise level sets the RMS left: 1 % of the signal's standard deviation
    y = cal.records[0].measured["tip"]
    assert fit.rms == pytest.approx(0.01 * np.std(y), rel=0.2)


def test_a_scale_factor_and_a_validation_record(tmp_path):
    train = _beam_record(tmp_path / "train.npz", seed=1)
    check = _beam_record(tmp_path / "check.npz", seed=2, duration=1.5)
    params = [
        {
            "name": "EI factor",
            "key": "arm.links[0].flexural_rigidity",
            "bounds": [0.3, 3.0],
            "scale": True,
        },
        EI_AND_DAMPING[1],
    ]
    config = _beam_config(tmp_path, [train, check], params)
    records = list(config.records)
    records[1] = type(records[1])(**{**records[1].__dict__, "role": "validation"})
    config = type(config)(**{**config.__dict__, "records": tuple(records)})
    cal = fa.calibrate(config)
    p = cal.parameters()["EI factor"]
    assert p["factor"] == pytest.approx(2.0 / 1.4, rel=0.02)
    assert p["value"] == pytest.approx(2.0, rel=0.02)
    summary = cal.summary()
    assert [r["name"] for r in summary["validation"]] == ["check.npz"]
    assert summary["validation"][0]["channels"]["tip"]["fit_percent"] > 90


def test_a_gauges_zero_offset_per_record_is_fitted_with_the_initial_states(tmp_path):
    """Each record's gauge reads its tip angle plus a zero of its own (+0.3 and -0.5
    of the signal's deviation): with ``offset = "fit"`` each record's offset is a
    nuisance unknown, fitted in training and estimated for the validation record, and
    the rigidity is recovered; without it the offsets bias the fit."""
    clean = StrainGauge(0, 0.0, 1e-3, "tip_angle")
    t = np.arange(round(2.0 * FS) + 1) / FS
    run = fa.simulate_prescribed(_beam(), t, _hub_motion, substeps=4)
    std = float(np.std(delayed(t, clean.raw(_beam(), run.q), 0.04)))
    train = _beam_record(tmp_path / "train.npz", seed=1, offset=0.3)
    check = _beam_record(tmp_path / "check.npz", seed=2, offset=-0.5)
    config = _beam_config(tmp_path, [train, check], EI_AND_DAMPING)
    config.tables["outputs"]["tip"]["offset"] = "fit"
    records = list(config.records)
    records[1] = type(records[1])(**{**records[1].__dict__, "role": "validation"})
    config = type(config)(**{**config.__dict__, "records": tuple(records)})
    cal = fa.calibrate(config)
    assert cal.parameters()["EI"]["value"] == pytest.approx(2.0, rel=0.01)
    assert cal.fit.nuisance[0][-1] == pytest.approx(0.3 * std, rel=0.05)
    for r in cal.records:
        assert r.channels["tip"].fit_percent > 95, r.role
    # the same records without the offsets' unknowns fit worse
    del config.tables["outputs"]["tip"]["offset"]
    plain = fa.calibrate(config)
    assert plain.records[1].channels["tip"].fit_percent < 90


def test_an_offset_is_fitted_or_absent(tmp_path):
    path = _beam_record(tmp_path / "run.npz", duration=0.5)
    data = {
        "calibration": {"data": "."},
        "arm": copy.deepcopy(BEAM_ARM),
        "outputs": {"tip": {**GAUGE, "offset": 0.1}},
        "parameters": EI_AND_DAMPING,
        "records": [
            {
                "file": path.name,
                "time": {"variable": "time", "unit": "s"},
                "inputs": [{"joint": 0, "kind": "angle", "variable": "theta", "unit": "rad"}],
                "outputs": {"tip": {"variable": "y", "unit": "rad"}},
            }
        ],
    }
    with pytest.raises(CalibrationError, match="'fit'") as err:
        CalibrationConfig.from_dict(data, "bad.toml", tmp_path)
    assert err.value.key == "outputs.tip.offset"


def _joint_record(path, *, stiffness=5.0, constant=0.05, delay=0.0, noise=0.01, seed=0, n=500):
    """A one-link arm behind a flexible joint driven by a motor current: the motor's
    encoder and the joint's deflection."""
    rng = np.random.default_rng(100 + seed)
    t = np.arange(n) / FS
    current = np.convolve(rng.standard_normal(n + 50), np.ones(25) / 25, "same")[:n] * 0.5
    drive = Drive(torque_constant=constant, gear_ratio=20, efficiency=0.8)
    arm = fa.FlexibleArm(
        [fa.Link(0.3, 1.0, 2.0, n_modes=0)],
        joints=[fa.LinearJoint(stiffness=stiffness, motor_inertia=0.01, motor_damping=0.05)],
    )
    run = fa.simulate_open_loop(
        arm, t, drive.joint_torque(current=current)[:, None], substeps=2, interpolation="linear"
    )
    enc = Encoder(0).raw(arm, run.q)
    defl = delayed(t, JointDeflection(0).raw(arm, run.q), delay)
    rng2 = np.random.default_rng(seed)
    enc = enc + noise * np.std(enc) * rng2.standard_normal(n)
    defl = defl + noise * np.std(defl) * rng2.standard_normal(n)
    np.savez(path, time=t, current=current, motor=enc, deflection=defl)
    return path


def _joint_config(tmp_path, path, parameters, deflection_delay=0.0):
    data = {
        "calibration": {"data": ".", "substeps": 2},
        "arm": {
            "links": [
                {"length": 0.3, "flexural_rigidity": 1.0, "linear_density": 2.0, "n_modes": 0}
            ],
            "joints": {
                "kind": "linear",
                "stiffness": 3.0,
                "motor_inertia": 0.01,
                "motor_damping": 0.05,
            },
        },
        "drives": [{"joint": 0, "torque_constant": 0.05, "gear_ratio": 20, "efficiency": 0.8}],
        "outputs": {
            "motor": {"kind": "encoder", "joint": 0},
            "deflection": {"kind": "joint_deflection", "joint": 0, "delay": deflection_delay},
        },
        "parameters": parameters,
        "records": [
            {
                "file": path.name,
                "time": {"variable": "time", "unit": "s"},
                "inputs": [{"joint": 0, "kind": "current", "variable": "current", "unit": "A"}],
                "outputs": {
                    "motor": {"variable": "motor", "unit": "rad"},
                    "deflection": {"variable": "deflection", "unit": "rad"},
                },
            }
        ],
    }
    return CalibrationConfig.from_dict(data, "joint.toml", tmp_path)


def _driven_rods_config(tmp_path, joints=None):
    """Two uniform rods (no modes), each joint driven by a motor with a rotor behind a
    gear (stage 1 of the Quanser rig's numbers on joint 1, a 7:1 elbow)."""
    arm = {
        "links": [
            {"length": 1.0, "flexural_rigidity": 1.0, "linear_density": 1.3, "n_modes": 0},
            {"length": 0.8, "flexural_rigidity": 1.0, "linear_density": 0.7, "n_modes": 0},
        ]
    }
    if joints is not None:
        arm["joints"] = joints
    data = {
        "calibration": {"data": "."},
        "arm": arm,
        "drives": [
            {"joint": 0, "torque_constant": 0.119, "gear_ratio": 100, "rotor_inertia": 6.28e-6},
            {"joint": 1, "torque_constant": 0.05, "gear_ratio": 7, "rotor_inertia": 4e-4},
        ],
        "outputs": {"hub": {"kind": "encoder", "joint": 0}},
        "parameters": [{"key": "drives[0].torque_constant", "bounds": [0.05, 0.2]}],
        "records": [
            {
                "file": "run.npz",
                "time": {"variable": "time", "unit": "s"},
                "inputs": [{"joint": 0, "kind": "current", "variable": "i", "unit": "A"}],
                "outputs": {"hub": {"variable": "theta", "unit": "rad"}},
            }
        ],
    }
    return CalibrationConfig.from_dict(data, "rods.toml", tmp_path)


def test_a_drives_rotor_is_counted_once_through_its_gear_by_hand(tmp_path):
    """Rotor 1 (J_r1 behind N1) on the base adds N1**2 J_r1 at theta_1; rotor 2 rides on
    rod 1 and turns at theta_1' + N2 theta_2', T = 1/2 J_r2 (theta_1' + N2 theta_2')**2:
    J_r2 at (theta_1, theta_1), N2 J_r2 at (theta_1, theta_2), N2**2 J_r2 at
    (theta_2, theta_2). A rotor taken as a hub turning with rod 2 would add N2**2 J_r2
    at all three."""
    jr1, n1, jr2, n2 = 6.28e-6, 100.0, 4e-4, 7.0
    q = np.array([0.3, -0.7])
    expected = two_rigid_rods_mass_matrix(1.3, 1.0, 0.7 * 0.8, 0.8, q[1])
    expected[0, 0] += n1**2 * jr1 + jr2
    expected[0, 1] += n2 * jr2
    expected[1, 0] += n2 * jr2
    expected[1, 1] += n2**2 * jr2
    arm = build_plant(_driven_rods_config(tmp_path)).arm
    np.testing.assert_allclose(arm.mass_matrix(q), expected, rtol=1e-13)
    # a rigid joint with a rotor of its own at the same gear carries both
    rigid = {"kind": "rigid", "motor_inertia": 0.02, "gear_ratio": 7}
    with pytest.raises(CalibrationError, match="gear ratio of 100") as err:
        build_plant(_driven_rods_config(tmp_path, rigid))
    assert err.value.key == "drives"
    del rigid["motor_inertia"]  # no rotor of its own: the drive's gear is the joint's
    arm = build_plant(_driven_rods_config(tmp_path, rigid)).arm
    np.testing.assert_allclose(arm.mass_matrix(q), expected, rtol=1e-13)


STIFFNESS = {"name": "k", "key": "arm.joints.stiffness", "bounds": [0.5, 50.0]}
TORQUE_CONSTANT = {
    "name": "Kt",
    "key": "drives[0].torque_constant",
    "bounds": [0.01, 0.2],
    "initial": 0.04,
}
MOTOR_DAMPING = {
    "name": "b",
    "key": "arm.joints.motor_damping",
    "bounds": [0.0, 1.0],
    "initial": 0.2,
}


def test_a_joint_stiffness_damping_torque_constant_and_delay_from_motor_currents(tmp_path):
    path = _joint_record(tmp_path / "joint.npz", delay=0.02)
    config = _joint_config(
        tmp_path, path, [STIFFNESS, TORQUE_CONSTANT, MOTOR_DAMPING], deflection_delay="estimate"
    )
    cal = fa.calibrate(config)
    p = cal.parameters()
    assert p["k"]["value"] == pytest.approx(5.0, rel=0.02)
    assert p["Kt"]["value"] == pytest.approx(0.05, rel=0.02)
    assert p["b"]["value"] == pytest.approx(0.05, rel=0.1)
    assert p["delay deflection"]["value"] == pytest.approx(0.02, abs=2e-3)
    for name, truth in (("k", 5.0), ("Kt", 0.05), ("b", 0.05)):
        assert abs(p[name]["value"] - truth) <= 3 * p[name]["ci95"], name


def test_a_stiffness_the_records_cannot_see_is_held_and_said_so(tmp_path):
    """Only the motor's encoder measured while the hub is prescribed: nothing in the
    record depends on the link's stiffness."""
    path = _beam_record(tmp_path / "run.npz")
    data = {
        "calibration": {"data": ".", "substeps": 2},
        "arm": copy.deepcopy(BEAM_ARM),
        "outputs": {"hub": {"kind": "encoder", "joint": 0}},
        "parameters": EI_AND_DAMPING,
        "records": [
            {
                "file": path.name,
                "time": {"variable": "time", "unit": "s"},
                "inputs": [{"joint": 0, "kind": "angle", "variable": "theta", "unit": "rad"}],
                "outputs": {"hub": {"variable": "theta", "unit": "rad"}},
            }
        ],
    }
    cal = fa.calibrate(CalibrationConfig.from_dict(data, "blind.toml", tmp_path))
    p = cal.parameters()
    for name, start in (("EI", 1.4), ("zeta", 0.01)):
        assert p[name]["determined"] is False and p[name]["ci95"] is None
        assert p[name]["value"] == start  # not moved
        assert "do not depend on it" in p[name]["note"]
    assert set(cal.summary()["undetermined"]) == {"EI", "zeta"}


def test_a_record_without_deflection_does_not_determine_a_stiffness(tmp_path):
    """The hub at rest: the strip never bends, whatever its rigidity."""
    t = np.arange(300) / FS
    np.savez(tmp_path / "rest.npz", time=t, theta=np.zeros_like(t), y=1e-6 * np.sin(t))
    config = _beam_config(tmp_path, [tmp_path / "rest.npz"], EI_AND_DAMPING[:1])
    cal = fa.calibrate(config)
    assert cal.parameters()["EI"]["determined"] is False


def test_confidence_intervals_cover_the_truth_at_their_stated_rate(tmp_path):
    """30 records of one joint with white noise on the measured deflection, each
    calibrated alone: the 95 % interval of the stiffness covers the truth in at least
    25 of them (P < 2 % for a true 95 % rate; the intervals assume white residuals)."""
    covered = 0
    for seed in range(30):
        path = _joint_record(tmp_path / f"j{seed}.npz", seed=seed, n=250, noise=0.05)
        config = _joint_config(tmp_path, path, [STIFFNESS])
        data = {**config.__dict__}
        records = [
            type(r)(**{**r.__dict__, "outputs": {"deflection": r.outputs["deflection"]}})
            for r in config.records
        ]
        config = type(config)(**{**data, "records": tuple(records)})
        cal = fa.calibrate(config, workers=1)
        p = cal.parameters()["k"]
        covered += abs(p["value"] - 5.0) <= p["ci95"]
    assert covered >= 25


GOOD = {
    "calibration": {"data": "."},
    "arm": copy.deepcopy(BEAM_ARM),
    "outputs": {"tip": dict(GAUGE)},
    "parameters": [{"key": "arm.links[0].flexural_rigidity", "bounds": [0.5, 5.0]}],
    "records": [
        {
            "file": "run.npz",
            "time": {"variable": "time", "unit": "s"},
            "inputs": [{"joint": 0, "kind": "angle", "variable": "theta", "unit": "rad"}],
            "outputs": {"tip": {"variable": "y", "unit": "rad"}},
        }
    ],
}


def _bad(change):
    data = copy.deepcopy(GOOD)
    change(data)
    return data


@pytest.mark.parametrize(
    ("change", "key"),
    [
        (lambda d: d["parameters"][0].update(key="trajectory.side"), "parameters[0].key"),
        (lambda d: d["parameters"][0].update(key="drives[0].gear_ratio"), "parameters[0].key"),
        (lambda d: d["parameters"][0].update(key="outputs.nope.delay"), "parameters[0].key"),
        (lambda d: d["parameters"][0].update(bounds=[5.0, 0.5]), "parameters[0].bounds"),
        (lambda d: d["parameters"][0].update(initial=9.0), "parameters[0].initial"),
        (lambda d: d["parameters"][0].update(bounds=[0.5]), "parameters[0].bounds"),
        (
            lambda d: d["records"][0]["outputs"].update(strain={"variable": "y", "unit": "1"}),
            "records[0].outputs.strain",
        ),
        (
            lambda d: d["records"][0]["inputs"][0].update(kind="voltage"),
            "records[0].inputs[0].kind",
        ),
        (lambda d: d["records"][0].update(role="test"), "records[0].role"),
        (lambda d: d["outputs"].update(x={"kind": "camera"}), "outputs.x.kind"),
        (lambda d: d["calibration"].update(substeps=0), "calibration.substeps"),
        (lambda d: d.update(trajectory={}), "trajectory"),
        (lambda d: d.update(records=[]), "records"),
    ],
)
def test_a_bad_configuration_is_one_error_naming_the_key(change, key):
    with pytest.raises(CalibrationError) as err:
        CalibrationConfig.from_dict(_bad(change), "bad.toml")
    assert err.value.key == key and str(err.value).startswith("bad.toml: ")


@pytest.mark.parametrize(
    ("change", "key", "match"),
    [
        (
            lambda d: d["records"][0]["outputs"]["tip"].update(variable="z"),
            "records[0].outputs.tip",
            "no variable 'z'",
        ),
        (
            lambda d: d["records"][0]["outputs"]["tip"].update(unit="furlong"),
            "records[0].outputs.tip.unit",
            "unknown unit",
        ),
        (lambda d: d["records"][0]["time"].update(unit="rad"), "records[0].time.unit", "time"),
        (lambda d: d["records"][0].update(stop=0.02), "records[0]", "too short"),
        (lambda d: d["records"][0].update(file="absent.npz"), "records[0].time", "no such file"),
        (
            lambda d: d["parameters"][0].update(key="arm.links[0].stiffness"),
            "parameters[0].key",
            "not a parameter there",
        ),
    ],
)
def test_a_record_that_cannot_be_read_is_one_error_naming_the_key(tmp_path, change, key, match):
    _beam_record(tmp_path / "run.npz", duration=0.5)
    config = CalibrationConfig.from_dict(_bad(change), "bad.toml", tmp_path)
    with pytest.raises(CalibrationError, match=match) as err:
        fa.calibrate(config)
    assert err.value.key == key


def test_an_arm_the_fit_stiffens_beyond_the_initial_step_is_replayed_at_its_own(tmp_path):
    """With substeps "auto" the initial arm's step (EI 300: 2 substeps at 250 Hz) is too
    long for the truth's (EI 1000: its second mode 1.8 times faster, beyond the margin of
    half again): the replays of a stiffer arm take the substeps it needs, so the fit
    reaches the truth instead of stalling where the initial step fails."""
    path = _beam_record(tmp_path / "stiff.npz", ei=1000.0, noise=0.0)
    params = [
        {
            "name": "EI",
            "key": "arm.links[0].flexural_rigidity",
            "bounds": [50.0, 3000.0],
            "initial": 300.0,
        }
    ]
    config = _beam_config(tmp_path, [path], params, substeps="auto")
    predictor = Predictor(config, load_records(config))
    values = [1000.0 if p.name == "EI" else p.initial for p in config.parameters]
    stiff = build_plant(config, np.array(values))
    assert predictor.for_plant(stiff).substeps > predictor.substeps > 1  # the case as stated
    cal = fa.calibrate(config)
    assert cal.parameters()["EI"]["value"] == pytest.approx(1000.0, rel=0.01)
    assert cal.records[0].channels["tip"].fit_percent > 95
