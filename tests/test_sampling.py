"""The sampled-data check: a period beyond the zero-order-hold stability bound is
refused before a run, with the pole and a period that works."""

from __future__ import annotations

import numpy as np
import pytest

import flexarm as fa
from flexarm.control.controllers import JacobianTransposePD, JointPD
from flexarm.control.linearize import closed_loop_poles
from flexarm.control.sampling import check_sampling
from flexarm.control.signals import reference_size
from flexarm.control.trajectories import Circle
from flexarm.sensing.sensors import JointSensor, TipSensor
from flexarm.sim import SimulationError, simulate

J, KP, KD = 1.0, 1.0, 10.0  # one rigid link on a hub: J theta'' = tau


@pytest.fixture(scope="module")
def rod():
    # rigid rod of negligible inertia next to a 1 kg m^2 hub
    return fa.FlexibleArm([fa.Link(1.0, 1.0, 1e-9, n_modes=0, hub_inertia=J)])


def jury_bound(j, kp, kd):
    """Largest stable period of a double integrator J theta'' = tau under
    tau_k = -kp theta_k - kd omega_k with a zero-order hold.

    Phi - Gamma K has trace 2 - kp dt^2/(2J) - kd dt/J and determinant
    1 - kd dt/J + kp dt^2/(2J); with z^2 + a1 z + a0 the Jury conditions are
    1 + a1 + a0 = kp dt^2/J > 0, 1 - a1 + a0 = 4 - 2 kd dt/J > 0 and |a0| < 1,
    i.e. dt < 2J/kd, dt < 2 kd/kp and kp dt^2 - 2 kd dt + 4J > 0."""
    disc = 4 * kd**2 - 16 * kp * j
    bounds = [2 * j / kd, 2 * kd / kp]
    if disc > 0:
        bounds.append((2 * kd - np.sqrt(disc)) / (2 * kp))
    return min(bounds)


def test_the_bound_of_a_double_integrator_in_closed_form(rod):
    ctrl = JointPD(kp=KP, kd=KD)
    bound = jury_bound(J, KP, KD)
    assert bound == pytest.approx(0.2)  # 2 J / kd, the other two are farther
    params = ctrl.parameters(rod)
    r = np.zeros(reference_size(1))
    just_under = check_sampling(
        rod, ctrl, JointSensor(), np.zeros(1), r, params, np.zeros(0), 0.199
    )
    just_over = check_sampling(rod, ctrl, JointSensor(), np.zeros(1), r, params, np.zeros(0), 0.201)
    assert just_under.stable and not just_over.stable
    assert just_over.period_too_long
    assert just_over.max_period == pytest.approx(bound, rel=1e-3)
    # the continuous poles of J s^2 + kd s + kp: the fastest is the one the message names
    fast = (-KD - np.sqrt(KD**2 - 4 * KP * J)) / (2 * J)
    assert just_over.fastest_pole.real == pytest.approx(fast, rel=1e-6)


def test_simulate_refuses_the_period_and_says_what_works(rod):
    ctrl = JointPD(kp=KP, kd=KD)
    path = Circle(center=(0.0, 0.0), radius=1.0, period=8.0)  # on the rod's reach
    with pytest.raises(ValueError, match=r"'dt'.*dt < 0\.2 s.*check_sampling=False") as err:
        simulate(rod, ctrl, path, dt=0.25, duration=2.0)
    assert "-9.899" in str(err.value)  # the pole, to four figures
    res = simulate(rod, ctrl, path, dt=0.15, duration=2.0)  # inside the bound: runs
    assert res.info["status"] == "ok"
    with pytest.raises(SimulationError):  # forced: it diverges as predicted
        simulate(
            rod, ctrl, path, dt=0.25, duration=200.0, initial_state=[0.1, 0.0], check_sampling=False
        )


def test_three_modes_paper_arm_is_refused_with_its_fastest_pole():
    """The hubless paper arm with three modes per link under the paper's law: the
    pole the check names agrees with the loop linearised through the compiled law."""
    arm = fa.FlexibleArm.paper(n_modes=3)
    with pytest.raises(ValueError, match="'dt'") as err:
        simulate(arm, duration=1.0)
    start = arm.forward_kinematics(arm.inverse_kinematics([3.0, -2.0]))  # the square's start
    poles = closed_loop_poles(arm, JacobianTransposePD.from_arm(arm), start)
    fastest = poles[np.argmax(np.abs(poles))].real
    assert fastest < -20_000
    named = float(str(err.value).split("fastest pole is ")[1].split(" rad/s")[0].replace(",", ""))
    assert named == pytest.approx(fastest, rel=1e-3)


def test_the_paper_arm_at_its_default_period_runs():
    res = simulate(fa.FlexibleArm.paper(), duration=0.05)
    assert res.info["status"] == "ok"


def test_a_loop_unstable_in_continuous_time_is_not_blamed_on_the_period():
    """JT-PD on the deflected tip is unstable at any period: no sampling error, it
    diverges as before."""
    with pytest.raises(SimulationError):
        simulate(fa.FlexibleArm.paper(), sensor=TipSensor(), duration=0.5)


def test_check_sampling_must_be_a_bool():
    with pytest.raises(TypeError, match="'check_sampling'"):
        simulate(fa.FlexibleArm.paper(), duration=0.01, check_sampling="no")
