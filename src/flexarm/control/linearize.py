"""Linear analysis of the arm: the open-loop plant, and closed loops through compiled laws.

:func:`linearize` gives the open-loop arm about a rest configuration (links
undeflected, motors at the link angles: an equilibrium under zero torque when
there is no gravity) as a :class:`~flexarm.control.statespace.StateSpace`
from the joint torques (N m) to a chosen output: what a sensor measures, the
deflected tip, or the joint angles; positions, and velocities with
``rates=True``. At rest the velocity terms are quadratic in the rates and drop
out, so the model is exact to first order::

    M(q0) dq'' = -K dq - D dq' + B dtau,   A = [[0, I], [-M^-1 K, -M^-1 D]],

``K`` the modal stiffness and the joint springs' tangent stiffness at zero
deflection, ``D`` the modal and motor damping and the friction's slope at
zero velocity (``MakkarFriction.slope``).

With gravity (``FlexibleArm(gravity=...)``) the rest configuration is the
posture that carries its weight, :meth:`FlexibleArm.equilibrium`: the links
sagging, the joints held by the static torques ``tau0``, the motors of flexible
joints ahead of their links by the springs' static deflection. ``K`` is then
its tangent stiffness, ``K + d2V/dq2`` (gravity's softening of a standing link
and stiffening of a hanging one, and the pendulum terms of the joints), and the
model's states, inputs and outputs are deviations from ``(q0, 0)``, ``tau0``
and ``y(q0)``: ``arm.equilibrium(theta)`` gives ``q0`` and ``tau0``. A posture
beyond a link's buckling load has no such model and raises
:class:`~flexarm.model.statics.UnstableEquilibriumError`.

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

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._types import F64
from .._validation import check_array, check_bool, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ..model.arm import FlexibleArm
from ..model.kinematics import lever_lengths, rigid_jacobian, rigid_point
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
from .statespace import StateSpace

__all__ = [
    "OUTPUTS",
    "closed_loop_matrix",
    "closed_loop_poles",
    "linearize",
    "measure",
    "rest_state",
]

OUTPUTS = ("sensor", "tip", "joints")

_OWNER = "closed_loop_matrix"


def measure(arm: FlexibleArm, sensor: Sensor, q: F64, dq: F64, h: float = 1e-5) -> F64:
    """The measurement ``y`` (:mod:`flexarm.control.signals`) of the state, undelayed
    (``h``: the difference step, rad or modal units, of the point's velocity).

    ``q`` and ``dq`` of shape ``(n_dof,)`` give ``y`` of shape ``(n_y,)``; of shape
    ``(m, n_dof)`` (states as rows), ``y`` of shape ``(m, n_y)`` in one pass.
    """
    single = np.ndim(q) == 1
    q, dq = np.atleast_2d(q), np.atleast_2d(dq)
    n_links = arm.n_links
    ya, yr, yp, yv, ym = (f(n_links) for f in (y_angles, y_rates, y_point, y_point_rate, y_modes))
    y = np.zeros((q.shape[0], measurement_size(n_links, sum(arm.n_modes))))
    cols = arm.motor_slice if arm.has_flexible_joints else slice(0, n_links)
    y[:, ya : ya + n_links], y[:, yr : yr + n_links] = q[:, cols], dq[:, cols]
    link, distance, _ = sensor.resolve(arm)
    if link < 0 or sensor.model == "paper":  # rigid kinematics of the encoder angles
        levers = arm.link_lengths if link < 0 else lever_lengths(arm.link_lengths, link, distance)
        pos, vel = rigid_point(levers, q[:, cols], dq[:, cols])
        assert vel is not None
        y[:, yp : yp + 2], y[:, yv : yv + 2] = pos, vel
    else:  # the deflected point; its velocity is linear in dq (central difference)

        def point(x: F64) -> F64:
            return arm.point_position(x, link, distance)

        y[:, yp : yp + 2] = point(q)
        speed = np.linalg.norm(dq, axis=1)
        moving = speed > 0.0
        if np.any(moving):
            v, u = speed[moving, None], dq[moving] / speed[moving, None]
            qm = q[moving]
            y[moving, yv : yv + 2] = v * (point(qm + h * u) - point(qm - h * u)) / (2 * h)
    y[:, ym:] = q[:, n_links : n_links + sum(arm.n_modes)]
    return y[0] if single else y


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
    q0 = rest_state(arm, theta)
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
        y = measure(arm, sensor, q, dq, 1e-5)
        tau = controller(0.0, y, r, params, controller.initial_state(arm))
        return np.concatenate([dq, arm.forward_dynamics(q, dq, tau)])

    x0 = np.concatenate([q0, np.zeros(n)])
    return _central_jacobian(field, x0, step * np.maximum(1.0, np.abs(x0)))


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


def rest_state(arm: FlexibleArm, theta: ArrayLike) -> F64:
    """``q`` at rest at joint angles ``theta`` (rad): links undeflected, motors (flexible
    joints) at the link angles. Shape (n_dof,)."""
    q0 = np.zeros(arm.n_dof)
    q0[: arm.n_links] = theta
    if arm.has_flexible_joints:
        q0[arm.motor_slice] = theta
    return q0


def _damping(arm: FlexibleArm) -> F64:
    """Linear damping at rest: modal and motor damping and the joints' friction slope
    at zero velocity, on the side it acts (N m s per coordinate rate)."""
    d = np.array(arm.damping_matrix, dtype=float)
    for jt, k in zip(arm.joints or (), arm.friction_coordinates, strict=True):
        if jt.friction is not None:
            d[k, k] += float(jt.friction.slope(0.0))
    return d


def _central_jacobian(fn: Callable[[F64], F64], x0: F64, steps: F64) -> F64:
    """``d fn / d x`` at ``x0`` by central differences, ``steps[j]`` along ``x_j``
    (fn: (m,) -> (k,); the result has shape (k, m))."""
    cols = []
    for j in range(x0.shape[0]):
        e = np.zeros_like(x0)
        e[j] = steps[j]
        cols.append((fn(x0 + e) - fn(x0 - e)) / (2 * e[j]))
    return np.stack(cols, axis=1)


def _position_jacobian(fn: Callable[[F64], F64], q0: F64, step: float = 1e-6) -> F64:
    """``d fn / d q`` at ``q0`` by central differences (fn: (n_dof,) -> (k,))."""
    return _central_jacobian(fn, q0, np.full(q0.shape[0], step))


def linearize(
    arm: FlexibleArm,
    theta: ArrayLike | None = None,
    *,
    position: ArrayLike | None = None,
    elbow: str = "positive",
    sensor: Sensor | None = None,
    output: str = "sensor",
    rates: bool = False,
) -> StateSpace:
    """The open-loop arm linearised at rest (module docstring), continuous time.

    Parameters
    ----------
    arm : FlexibleArm
    theta : array_like, shape (n_links,), optional
        Joint angles of the rest configuration, rad (default: straight, zeros).
    position : array_like, shape (2,), optional
        Instead of ``theta``: the end effector's rest point, m (two-link arms,
        inverse kinematics on the ``elbow`` branch).
    elbow : {"positive", "negative"}
    sensor : JointSensor, PointSensor or TipSensor, optional
        For ``output="sensor"`` (default: joint encoders).
    output : {"sensor", "tip", "joints"}
        What the sensor measures (the encoder angles; the point, deflected or,
        for ``model="paper"``, the rigid kinematics of the encoder angles), the
        deflected tip (x, y), or the link-side joint angles.
    rates : bool
        Add the outputs' rates after the positions.

    Returns
    -------
    StateSpace
        States ``(q, dq)`` named after :attr:`FlexibleArm.coordinate_names`
        (rates prefixed ``d``), inputs ``tau1..tauN`` (N m), outputs in m or rad
        (and m/s, rad/s). Use ``.discretize(dt)`` for the sampled model and
        ``.to_control()`` for python-control. With gravity, deviations from
        the posture :meth:`FlexibleArm.equilibrium` gives (module docstring).

    Raises
    ------
    UnstableEquilibriumError
        With gravity, if the posture puts a link beyond its buckling load.
    """
    owner = "linearize"
    if not isinstance(arm, FlexibleArm):
        raise InvalidTypeError(
            f"The 'arm' parameter of {owner} must be a FlexibleArm. "
            f"Got {type(arm).__name__} instead."
        )
    check_option(output, "output", owner, OUTPUTS)
    sensor = check_sensor(sensor, owner)
    check_bool(rates, "rates", owner)
    n, n_links = arm.n_dof, arm.n_links
    if position is not None:
        if theta is not None:
            raise InvalidValueError(
                f"The 'position' parameter of {owner} excludes 'theta'. Got both instead."
            )
        check_option(elbow, "elbow", owner, ("positive", "negative"))
        angles = np.asarray(
            arm.inverse_kinematics(check_array(position, "position", owner, shape=(2,)), elbow),
            dtype=float,
        )
    elif theta is None:
        angles = np.zeros(n_links)
    else:
        angles = check_array(theta, "theta", owner, shape=(n_links,))
    q0 = rest_state(arm, angles)
    stiffness = arm.stiffness_matrix
    if arm.gravity is not None:  # the posture that carries its weight
        posture = arm.equilibrium(angles)
        q0, stiffness = posture.q, posture.stiffness
    mass = np.asarray(arm.mass_matrix(q0).real, dtype=float)
    if not np.all(np.isfinite(mass)) or np.linalg.cond(mass) > 1.0 / np.finfo(float).eps:
        raise InvalidValueError(
            f"The 'arm' parameter of {owner} has a mass matrix singular to working precision "
            f"at theta = {angles.tolist()} rad: its masses and inertias span more orders of "
            "magnitude than float64 resolves."
        )
    a = np.zeros((2 * n, 2 * n))
    a[:n, n:] = np.eye(n)
    a[n:, :n] = -np.linalg.solve(mass, stiffness)
    a[n:, n:] = -np.linalg.solve(mass, _damping(arm))
    b = np.zeros((2 * n, n_links))
    b[n:] = np.linalg.solve(mass, arm.input_matrix)
    cq, names = _output_map(arm, sensor, output, q0)
    c = np.zeros((cq.shape[0] * (2 if rates else 1), 2 * n))
    c[: cq.shape[0], :n] = cq
    if rates:
        c[cq.shape[0] :, n:] = cq  # at rest, d/dt g(q) = (dg/dq) dq
        names = [*names, *(f"d{s}" for s in names)]
    coords = arm.coordinate_names
    return StateSpace(
        a,
        b,
        c,
        None,
        None,
        [*coords, *(f"d{s}" for s in coords)],
        [f"tau{i + 1}" for i in range(n_links)],
        names,
    )


def _output_map(arm: FlexibleArm, sensor: Sensor, output: str, q0: F64) -> tuple[F64, list[str]]:
    """``d y / d q`` at ``q0`` and the output names."""
    n_links = arm.n_links
    encoders = arm.motor_slice if arm.has_flexible_joints else slice(0, n_links)
    if output == "joints":
        cq = np.zeros((n_links, arm.n_dof))
        cq[:, :n_links] = np.eye(n_links)
        return cq, [f"theta{i + 1}" for i in range(n_links)]
    if output == "tip":
        return _position_jacobian(arm.tip_position, q0), ["x_tip", "y_tip"]
    link, distance, _ = sensor.resolve(arm)
    if link < 0:
        cq = np.zeros((n_links, arm.n_dof))
        cq[:, encoders] = np.eye(n_links)
        return cq, [arm.coordinate_names[k] for k in range(arm.n_dof)[encoders]]
    if sensor.model == "paper":
        levers = lever_lengths(arm.link_lengths, link, distance)
        cq = np.zeros((2, arm.n_dof))
        cq[:, encoders] = rigid_jacobian(levers, q0[encoders])
        return cq, ["x_sensor", "y_sensor"]

    def point(q: F64) -> F64:
        return arm.point_position(q, link, distance)

    return _position_jacobian(point, q0), ["x_sensor", "y_sensor"]
