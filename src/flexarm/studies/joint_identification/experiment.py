"""The joint study's experiment: the test arm, the random-torque run, the noisy measurements.

:func:`joint_test_arm` builds the plant; :func:`run_excitation` drives it open
loop with the seeded random command through the drive's static map
(:class:`JointRecord`, the truth the simulation knows); :func:`measure` adds the
sensors' noise (:class:`JointMeasurements`, what the identification sees).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..._types import F64
from ..._validation import check_real
from ...model.arm import FlexibleArm
from ...model.joints import LinearJoint, MakkarFriction, NonlinearJoint
from ...model.link import Link
from ...sim.open_loop import simulate_open_loop
from .parameters import JointExcitation, JointSensors

__all__ = ["JointMeasurements", "JointRecord", "joint_test_arm", "measure", "run_excitation"]


def joint_test_arm(
    joint: NonlinearJoint | LinearJoint | None = None, motor_damping: float = 10.0
) -> FlexibleArm:
    """One rigid link (the paper's 4.5 m link as a rod) on a flexible joint with friction.

    Parameters
    ----------
    joint : NonlinearJoint or LinearJoint, optional
        Default: :meth:`NonlinearJoint.default` with :meth:`MakkarFriction.default`
        and the given ``motor_damping``.
    motor_damping : float
        Motor-side damping ``c_m`` for the default joint, N m s/rad: a drive's
        back-EMF damping, which damps the joint mode (about 120–180 rad/s)
        to a damping ratio of about 0.1.

    Returns
    -------
    FlexibleArm
        ``q = (theta, q_m)``.
    """
    if joint is None:
        base = NonlinearJoint.default(friction=MakkarFriction.default())
        joint = NonlinearJoint(
            base.a1,
            base.a2,
            base.ksw,
            base.asw,
            base.motor_inertia,
            friction=base.friction,
            motor_damping=check_real(motor_damping, "motor_damping", "joint_test_arm"),
        )
    link = Link(4.5, 1676.0, 0.335, n_modes=0)
    return FlexibleArm(links=(link,), joints=(joint,))


@dataclass(frozen=True)
class JointRecord:
    """The experiment as the simulation knows it (true signals at every sample).

    Attributes
    ----------
    dt : float
        Sample period, s.
    q, q_m : ndarray, shape (n,)
        Link and motor angles, rad.
    v, v_m : ndarray, shape (n,)
        Link and motor rates, rad/s.
    tau : ndarray, shape (n,)
        Applied torque, held over each sample period, N m.
    command : ndarray, shape (n_holds + 1,)
        The commanded torque of each hold, N m (``tau = phi(command)``).
    hold_steps : int
        Samples per hold.
    status : str
        The simulator's status (``"ok"``; a divergence raises
        :class:`~flexarm.sim.results.SimulationError`).
    """

    dt: float
    q: F64
    q_m: F64
    v: F64
    v_m: F64
    tau: F64
    command: F64
    hold_steps: int
    status: str

    @property
    def n_holds(self) -> int:
        """Whole holds in the record."""
        return int(self.command.shape[0]) - 1

    @property
    def hold_starts(self) -> NDArray[np.int_]:
        """Sample index at the start of each hold, shape (n_holds,)."""
        out: NDArray[np.int_] = np.arange(self.n_holds) * self.hold_steps
        return out


@dataclass(frozen=True)
class JointMeasurements:
    """The noisy signals (:class:`~flexarm.studies.joint_identification.JointSensors`).

    Attributes
    ----------
    q, q_m : ndarray, shape (n,)
        Link and motor encoders, rad.
    v, v_m : ndarray, shape (n,)
        Link and motor rates, rad/s.
    tau : ndarray, shape (n,)
        Applied torque from the motor current, N m.
    tau_s : ndarray, shape (n,)
        Joint torque sensor (spring torque), N m.
    acceleration : ndarray, shape (n_holds,)
        Link accelerometer after its integrate-and-dump filter: the mean link
        acceleration over each hold, rad/s**2.
    """

    q: F64
    q_m: F64
    v: F64
    v_m: F64
    tau: F64
    tau_s: F64
    acceleration: F64


def run_excitation(
    arm: FlexibleArm, excitation: JointExcitation, rng: np.random.Generator
) -> JointRecord:
    """Drive ``arm`` open loop with the random command through the drive's map.

    The commands (:meth:`JointExcitation.commands`) are drawn from ``rng``, one
    per hold (``n_holds + 1`` of them), and ``tau = drive(u)`` is held for
    ``hold_steps`` samples: :func:`flexarm.simulate_open_loop` with the samples
    held over each period ``dt`` (zero-order hold), one RK4 step per period.

    Parameters
    ----------
    arm : FlexibleArm
        One link on a flexible joint (:func:`joint_test_arm`).
    excitation : JointExcitation
    rng : numpy.random.Generator
    """
    dt, steps, n_steps = excitation.dt, excitation.hold_steps, excitation.n_steps
    n_holds = n_steps // steps
    command = excitation.commands(n_holds + 1, rng)
    applied = excitation.drive(command)
    per_sample = np.repeat(applied, steps)[: n_steps + 1]  # (n_holds + 1) steps > n_steps
    t = dt * np.arange(n_steps + 1)
    res = simulate_open_loop(arm, t, per_sample[:, None], interpolation="zoh")
    m = arm.motor_slice.start
    return JointRecord(
        dt=dt,
        q=res.q[:, 0],
        q_m=res.q[:, m],
        v=res.dq[:, 0],
        v_m=res.dq[:, m],
        tau=res.tau[:, 0],
        command=command,
        hold_steps=steps,
        status=str(res.info["status"]),
    )


def measure(
    record: JointRecord,
    joint: NonlinearJoint | LinearJoint,
    sensors: JointSensors,
    rng: np.random.Generator,
) -> JointMeasurements:
    """Add the sensors' Gaussian noise to the true signals (drawn from ``rng`` in a fixed order).

    Parameters
    ----------
    record : JointRecord
    joint : NonlinearJoint or LinearJoint
        The joint, for the true spring torque the torque sensor reads.
    sensors : JointSensors
    rng : numpy.random.Generator
    """

    def noisy(x: F64, sigma: float) -> F64:
        out: F64 = x + sigma * rng.standard_normal(x.shape[0]) if sigma > 0 else x.copy()
        return out

    q = noisy(record.q, sensors.angle_noise)
    q_m = noisy(record.q_m, sensors.angle_noise)
    v = noisy(record.v, sensors.rate_noise)
    v_m = noisy(record.v_m, sensors.rate_noise)
    tau = noisy(record.tau, sensors.torque_noise)
    spring = np.asarray(joint.torque(record.q_m - record.q), dtype=np.float64)
    tau_s = noisy(spring, sensors.torque_sensor_noise)
    starts, steps = record.hold_starts, record.hold_steps
    mean_acc = (record.v[starts + steps] - record.v[starts]) / (steps * record.dt)
    acceleration = noisy(mean_acc, sensors.acceleration_noise)
    return JointMeasurements(q, q_m, v, v_m, tau, tau_s, acceleration)
