"""Instruments of a rig: a strain gauge and a tip angle against the closed form of a
cantilever under a static tip load, encoders with their quantum, delays per channel."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.sensing.instruments import (
    Encoder,
    JointDeflection,
    StrainGauge,
    TipAngle,
    delayed,
    measure,
)

L, EI, RHO, P, T = 0.5, 3.0, 0.8, 2.0, 0.002  # m, N m^2, kg/m, N, m


def _static_tip_load(n_modes):
    """The modal coordinates of a cantilever under a static tip force P: K d = phi(L) P."""
    arm = fa.FlexibleArm(
        [fa.Link(L, EI, RHO, n_modes=n_modes)], boundary="clamped-free", geometric_stiffening=False
    )
    stiffness = arm.stiffness_matrix[1:, 1:]
    d = np.linalg.solve(stiffness, arm.modes[0].shape(np.array([L]))[:, 0] * P)
    return arm, np.r_[0.0, d][None, :]


def test_strain_and_tip_angle_converge_to_the_cantilever_closed_form():
    """w(x) = P x^2 (3L - x) / (6 EI): root strain (T/2) P L / EI, strain at L/2 half
    of it, tip angle w(L)/L = P L^2 / (3 EI); the gauge's tip-angle form of the root
    strain equals the tip angle for this shape."""
    root = 0.5 * T * P * L / EI
    tip = P * L**2 / (3 * EI)
    errors = []
    for n in (2, 4, 8, 12):
        arm, q = _static_tip_load(n)
        strain = StrainGauge(0, 0.0, T).raw(arm, q)[0]
        errors.append(abs(strain / root - 1))
        if n == 12:
            assert strain == pytest.approx(root, rel=2e-3)
            assert StrainGauge(0, L / 2, T).raw(arm, q)[0] == pytest.approx(root / 2, rel=2e-3)
            assert StrainGauge(0, 0.0, T, "tip_angle").raw(arm, q)[0] == pytest.approx(
                tip, rel=2e-3
            )
            assert TipAngle(0).raw(arm, q)[0] == pytest.approx(tip, rel=1e-4)
    assert errors == sorted(errors, reverse=True)  # more modes, closer


def test_encoders_read_motors_behind_flexible_joints_and_round_to_their_quantum():
    arm = fa.FlexibleArm.paper(joints=[fa.LinearJoint.default()] * 2)
    rng = np.random.default_rng(1)
    q = rng.normal(size=(50, arm.n_dof))
    t = np.arange(50) * 1e-3
    quantum = 2 * np.pi / 4096
    enc = Encoder(1, quantum=quantum).measure(arm, t, q)
    motor = q[:, arm.motor_slice][:, 1]
    np.testing.assert_allclose(enc / quantum, np.round(enc / quantum), atol=1e-9)
    assert np.max(np.abs(enc - motor)) <= quantum / 2 + 1e-15
    np.testing.assert_array_equal(
        JointDeflection(0).raw(arm, q), q[:, 0] - q[:, arm.motor_slice][:, 0]
    )
    rigid = fa.FlexibleArm.paper()
    np.testing.assert_array_equal(Encoder(0).raw(rigid, q[:, : rigid.n_dof]), q[:, 0])


def test_a_channel_delay_shifts_by_whole_samples_and_holds_the_first_value():
    t = np.arange(100) * 2e-3
    signal = np.sin(7 * t)
    out = delayed(t, signal, 10 * 2e-3)
    np.testing.assert_allclose(out[10:], signal[:-10], atol=1e-15)
    assert np.all(out[:10] == signal[0])
    half = delayed(t, signal, 1e-3)  # between samples: linear interpolation
    np.testing.assert_allclose(half[1:], 0.5 * (signal[1:] + signal[:-1]))
    arm = fa.FlexibleArm.paper()
    q = np.column_stack([signal, np.zeros((100, 3))])
    got = measure(arm, t, q, {"a": Encoder(0), "b": Encoder(0, delay=0.02)})
    np.testing.assert_array_equal(got["b"], delayed(t, got["a"], 0.02))


@pytest.mark.parametrize(
    ("make", "error", "match"),
    [
        (lambda: Encoder(-1), InvalidValueError, "'joint'"),
        (lambda: Encoder(0, quantum=-1.0), InvalidValueError, "'quantum'"),
        (lambda: Encoder(0, delay=-0.1), InvalidValueError, "'delay'"),
        (lambda: StrainGauge(0, thickness=0.0), InvalidValueError, "'thickness'"),
        (lambda: StrainGauge(0, form="volts"), InvalidValueError, "'form'"),
        (lambda: StrainGauge(0.5), InvalidTypeError, "'link'"),
    ],
)
def test_instruments_refuse_bad_parameters(make, error, match):
    with pytest.raises(error, match=match):
        make()


def test_instruments_refuse_what_the_arm_does_not_have():
    arm = fa.FlexibleArm.paper()
    q, t = np.zeros((3, arm.n_dof)), np.zeros(3) + np.arange(3)
    with pytest.raises(InvalidValueError, match="'joint'"):
        Encoder(2).measure(arm, t, q)
    with pytest.raises(InvalidValueError, match="flexible joints"):
        JointDeflection(0).measure(arm, t, q)
    with pytest.raises(InvalidValueError, match="'position'"):
        StrainGauge(0, position=5.0).measure(arm, t, q)
    with pytest.raises(InvalidValueError, match="'q'"):
        Encoder(0).measure(arm, t, q[:, :3])
    with pytest.raises(InvalidTypeError, match="'arm'"):
        Encoder(0).measure("paper", t, q)  # type: ignore[arg-type]
