"""Linearised closed loops: why a loop diverges, before simulating it.

:func:`closed_loop_matrix` linearises ``x' = f(x)``, ``x = (q, dq)``, of an arm
under a controller reading a sensor, in continuous time (the law applied
continuously, undelayed, noise-free), about the arm at rest with its end
effector at a given point, straight links and the law's reference there. The
eigenvalues (:func:`closed_loop_poles`) tell whether that equilibrium is stable
(all real parts < 0) and, with the control period, whether a sampled loop can
be: the fastest real pole ``-a`` needs roughly ``dt < 2.8 / a`` under RK4 with a
zero-order hold.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.kinematics import lever_lengths, rigid_point
from ..sensing.sensors import Sensor, check_sensor
from .controllers import Controller
from .signals import (
    measurement_size,
    r_angles,
    r_position,
    reference_size,
    y_angles,
    y_modes,
    y_point,
    y_point_rate,
    y_rates,
)

__all__ = ["closed_loop_matrix", "closed_loop_poles"]

F64 = NDArray[np.float64]
_OWNER = "closed_loop_matrix"


def _measure(arm: FlexibleArm, sensor: Sensor, q: F64, dq: F64, h: float) -> F64:
    """The measurement ``y`` (:mod:`flexarm.control.signals`) of the state, undelayed
    (``h``: the difference step, rad or modal units, of the point's velocity)."""
    n_links = arm.n_links
    ya, yr, yp, yv, ym = (f(n_links) for f in (y_angles, y_rates, y_point, y_point_rate, y_modes))
    y = np.zeros(measurement_size(n_links, sum(arm.n_modes)))
    cols = arm.motor_slice if arm.has_flexible_joints else slice(0, n_links)
    y[ya : ya + n_links], y[yr : yr + n_links] = q[cols], dq[cols]
    link, distance, _ = sensor.resolve(arm)
    if link < 0:  # rigid kinematics of the encoder angles
        pos, vel = rigid_point(arm.link_lengths, q[cols], dq[cols])
        assert vel is not None
        y[yp : yp + 2], y[yv : yv + 2] = pos, vel
    else:  # the deflected point; its velocity is linear in dq (central difference)

        def point(x: F64) -> F64:
            return arm.point_position(x, link, distance)

        y[yp : yp + 2] = point(q)
        speed = float(np.linalg.norm(dq))
        if speed > 0.0:
            u = dq / speed
            y[yv : yv + 2] = speed * (point(q + h * u) - point(q - h * u)) / (2 * h)
    y[ym:] = q[n_links : n_links + sum(arm.n_modes)]
    return y


def closed_loop_matrix(
    arm: FlexibleArm,
    controller: Controller,
    position: ArrayLike,
    sensor: Sensor | None = None,
    *,
    elbow: str = "positive",
    step: float = 1e-6,
) -> F64:
    """The state matrix ``A`` of the loop linearised about a rest point.

    Parameters
    ----------
    arm : FlexibleArm
        A two-link arm (the rest point comes from inverse kinematics).
    controller : Controller
        Evaluated continuously through its compiled law.
    position : array_like, shape (2,)
        End-effector rest point, m.
    sensor : JointSensor, PointSensor or TipSensor, optional
        Default joint encoders.
    elbow : {"positive", "negative"}
        Inverse-kinematics branch.
    step : float
        Relative central-difference step.

    Returns
    -------
    ndarray, shape (2 n_dof, 2 n_dof)
        ``d/dx [dq, ddq]`` at ``x = (q0, 0)``: straight links, the end effector at
        ``position``, motors (flexible joints) at the link angles.
    """
    if arm.n_links != 2:
        raise InvalidValueError(
            f"The 'arm' parameter of {_OWNER} must have two links (inverse kinematics). "
            f"Got {arm.n_links} links instead."
        )
    if not isinstance(controller, Controller):
        raise InvalidTypeError(
            f"The 'controller' parameter of {_OWNER} must be a flexarm Controller. "
            f"Got {type(controller).__name__} instead."
        )
    sensor = check_sensor(sensor, _OWNER)
    target = check_array(position, "position", _OWNER, shape=(2,))
    check_option(elbow, "elbow", _OWNER, ("positive", "negative"))
    step = check_real(step, "step", _OWNER, positive=True)
    n, n_links = arm.n_dof, arm.n_links
    theta = np.asarray(arm.inverse_kinematics(target, elbow=elbow), dtype=float)
    q0 = np.zeros(n)
    q0[:n_links] = theta
    if arm.has_flexible_joints:
        q0[arm.motor_slice] = theta
    link, distance, _ = sensor.resolve(arm)
    r = np.zeros(reference_size(n_links))
    short_of_tip = link >= 0 and not (
        link == n_links - 1 and distance == arm.link_lengths[n_links - 1]
    )
    if short_of_tip:
        target = rigid_point(lever_lengths(arm.link_lengths, link, distance), theta)[0]
    r[r_position(n_links) : r_position(n_links) + 2] = target
    r[r_angles(n_links) : r_angles(n_links) + n_links] = theta
    params = np.ascontiguousarray(controller.parameters_for(arm, sensor), dtype=float)

    def field(x: F64) -> F64:
        q, dq = x[:n], x[n:]
        y = _measure(arm, sensor, q, dq, 1e-5)
        tau = controller(0.0, y, r, params, controller.initial_state(arm))
        return np.concatenate([dq, arm.forward_dynamics(q, dq, tau)])

    x0 = np.concatenate([q0, np.zeros(n)])
    a = np.empty((2 * n, 2 * n))
    for j in range(2 * n):
        e = np.zeros(2 * n)
        e[j] = step * max(1.0, abs(x0[j]))
        a[:, j] = (field(x0 + e) - field(x0 - e)) / (2 * e[j])
    return a


def closed_loop_poles(
    arm: FlexibleArm,
    controller: Controller,
    position: ArrayLike,
    sensor: Sensor | None = None,
    *,
    elbow: str = "positive",
    step: float = 1e-6,
) -> NDArray[np.complex128]:
    """Eigenvalues of :func:`closed_loop_matrix`, rad/s, sorted by real part (largest first).

    The parameters are those of :func:`closed_loop_matrix`.

    Examples
    --------
    >>> import flexarm as fa
    >>> from flexarm.control.controllers import JacobianTransposePD
    >>> from flexarm.sensing.sensors import TipSensor
    >>> arm = fa.FlexibleArm.paper()
    >>> poles = closed_loop_poles(arm, JacobianTransposePD.from_arm(arm), (7.0, -2.0), TipSensor())
    >>> bool(poles[0].real > 0)   # tip feedback: unstable
    True
    """
    a = closed_loop_matrix(arm, controller, position, sensor, elbow=elbow, step=step)
    poles = np.asarray(np.linalg.eigvals(a), dtype=np.complex128)
    return poles[np.argsort(-poles.real, kind="stable")]
