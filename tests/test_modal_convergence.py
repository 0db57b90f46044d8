"""The modal convergence check, the spin-up study and the paper arm's notes."""

from __future__ import annotations

import json

import numpy as np
import pytest

import flexarm as fa
from flexarm.errors import InvalidTypeError, InvalidValueError
from flexarm.sim.prescribed import simulate_prescribed
from flexarm.studies.modal_convergence import convergence_check
from flexarm.studies.spin_up import KANE_LINK, kane_motion, spin_up

ARM = fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335)] * 2)  # clamped-mass, stiffening
T = np.linspace(0.0, 1.0, 201)


def pulse(t: float) -> list[float]:
    s = np.sin(np.pi * t) ** 2
    return [5.0 * s, -2.0 * s]


def test_errors_fall_and_the_recommendation_is_the_fewest_modes_within_tolerance():
    check = convergence_check(ARM, T, torque=pulse, n_modes=(1, 2, 3, 5), tolerance=0.01)
    errs = [c.relative_deflection_error.max() for c in check.cases]
    assert errs[0] > errs[1] > errs[2] > errs[3] == 0.0
    assert check.converged
    first = next(
        i
        for i, c in enumerate(check.cases)
        if max(c.relative_deflection_error.max(), c.relative_tip_error) <= 0.01
    )
    assert check.recommended == check.cases[first].n_modes
    assert check.boundary == "clamped-mass"
    # the reference's own deflections set the scale
    richest = fa.simulate_open_loop(ARM.with_modes(5), T, pulse, substeps=4)
    np.testing.assert_allclose(check.peak_deflection, np.abs(richest.link_deflections).max(0))
    assert "recommended" in check.text()
    json.dumps(check.to_dict())


def test_no_recommendation_when_the_richest_bases_disagree():
    check = convergence_check(ARM, T, torque=pulse, n_modes=(1, 2), tolerance=1e-4)
    assert not check.converged and check.recommended is None
    assert "not converged" in check.text()


def test_prescribed_motion_and_any_run_give_the_same_comparison():
    motion = kane_motion(omega=2.0, ramp=2.0)
    arm = fa.FlexibleArm([KANE_LINK])
    t = np.linspace(0.0, 3.0, 301)
    by_motion = convergence_check(arm, t, motion=motion, n_modes=(1, 3))
    by_run = convergence_check(
        arm, run=lambda a: simulate_prescribed(a, t, motion, substeps=4), n_modes=(1, 3)
    )
    np.testing.assert_allclose(
        by_motion.cases[0].deflection_error, by_run.cases[0].deflection_error, rtol=1e-12
    )


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"torque": pulse, "motion": kane_motion()}, InvalidValueError, "exactly one"),
        ({}, InvalidValueError, "exactly one"),
        ({"torque": pulse, "t": None}, InvalidValueError, "'t'"),
        ({"torque": pulse, "n_modes": (3,)}, InvalidValueError, "'n_modes'"),
        ({"torque": pulse, "n_modes": (3, 2)}, InvalidValueError, "'n_modes'"),
        ({"torque": pulse, "boundary": "pinned"}, InvalidValueError, "'boundary'"),
        ({"torque": pulse, "tolerance": 0.0}, InvalidValueError, "'tolerance'"),
    ],
)
def test_convergence_check_rejects_bad_input(kwargs, error, match):
    args = {"t": T} | kwargs
    with pytest.raises(error, match=match):
        convergence_check(ARM, **args)


def test_convergence_check_needs_a_flexible_arm():
    with pytest.raises(InvalidTypeError, match="'arm'"):
        convergence_check("paper", T, torque=pulse)


def test_spin_up_study_is_the_kane_profile():
    """theta(T) = Omega T / 2 (the ramp's mean rate is Omega / 2) and the rate reaches
    Omega smoothly (zero acceleration at both ends of the ramp)."""
    motion = kane_motion(6.0, 15.0)
    th, dth, ddth = motion(np.array([0.0, 15.0, 20.0]))
    np.testing.assert_allclose(th, [0.0, 45.0, 75.0], atol=1e-12)
    np.testing.assert_allclose(dth, [0.0, 6.0, 6.0], atol=1e-12)
    np.testing.assert_allclose(ddth, [0.0, 0.0, 0.0], atol=1e-12)
    res = spin_up(2.0, duration=2.0)
    np.testing.assert_allclose(res.q[:, 0], motion(res.t)[0] / 3.0, atol=1e-12)  # Omega 2 vs 6
    with pytest.raises(InvalidValueError, match="'arm'"):
        spin_up(2.0, arm=fa.FlexibleArm([KANE_LINK]), geometric_stiffening=False)


def test_paper_arm_note_is_what_the_docstring_says():
    note = fa.model.validity.PAPER_MODEL_NOTE
    assert "clamped-free" in note and "stiff" in note
    assert fa.model.validity.PAPER_DEFLECTION_ERROR > 1.0
    assert "1.2 times the peak" in fa.FlexibleArm.paper.__doc__
