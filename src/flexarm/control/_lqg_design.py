"""The LQG's design, grid point by grid point: the regulator and filter blocks, and
with gravity the operating table (holding torques and sag) of each posture.

Internal to :mod:`flexarm.control.lqg`: the blocks are cached, so that runs sharing
a design solve its Riccati equations once.
"""

from __future__ import annotations

import functools
from typing import NamedTuple

import numpy as np

from .._types import F64
from ..model.arm import FlexibleArm
from ..model.kinematics import lever_lengths, rigid_point
from ..sensing.sensors import JointSensor, PointSensor, Sensor
from ._lqg_layout import pack_block
from .design import kalman, lqr
from .gravity_compensation import holding_torques, scratch_size
from .linearize import linearize, measure
from .signals import y_angles, y_point

__all__ = ["TABLE_REFINEMENT", "Geometry", "design_blocks", "operating_table", "sensor_of"]


class Geometry(NamedTuple):
    """What a design needs of the sensor: where it is and which model it follows."""

    link: int
    distance: float
    model: str


def sensor_of(geometry: Geometry) -> Sensor:
    if geometry.link < 0:
        return JointSensor()
    return PointSensor(geometry.link, geometry.distance, model=geometry.model)


@functools.lru_cache(maxsize=64)
def design_blocks(
    model: FlexibleArm,
    geometry: Geometry,
    dt: float,
    grid: tuple[float, ...],
    weights: tuple[float, float, float],
    noises: tuple[float, float, float],
    shoulder: tuple[float, ...] | None = None,
) -> tuple[list[F64], int]:
    """Per grid point ``Phi, Gamma, C, K, M`` flattened, and the
    measurement's size (cached: runs that share a design solve its Riccati equations
    once). ``shoulder`` None: at ``theta_1 = 0``; else on the grid of both angles,
    shoulder-major, about the gravity equilibrium of each posture."""
    qp, qv, rt = weights
    tn, pos_noise, vel_noise = noises
    sensor = sensor_of(geometry)
    nx, n_links = 2 * model.n_dof, model.n_links
    blocks = []
    ny = 0
    postures = [(0.0, th) for th in grid]
    if shoulder is not None:
        postures = [(t1, th) for t1 in shoulder for th in grid]
    for posture in postures:
        theta = np.array(posture)
        meas = linearize(model, theta, sensor=sensor, rates=True).discretize(dt)
        tip = linearize(model, theta, output="tip", rates=True)
        ny = meas.n_outputs
        half = ny // 2
        q = tip.C.T @ np.diag([qp, qp, qv, qv]) @ tip.C
        q += 1e-9 * np.trace(q) / nx * np.eye(nx)
        reg = lqr(meas, q, rt * np.eye(n_links))
        rn = np.diag([pos_noise**2] * half + [vel_noise**2] * half)
        est = kalman(meas, meas.B, tn**2 * np.eye(n_links), rn)
        blocks.append(pack_block(meas.A, meas.B, meas.C, reg.K, est.M))
    for b in blocks:
        b.flags.writeable = False
    return blocks, ny


TABLE_REFINEMENT = 4
"""The operating table's grid is this many times finer than the design's (the
holding torques vary by some 100 N m over the square: interpolated on the design's
grid they would be off by about a newton metre, a standing error of the loop)."""


@functools.lru_cache(maxsize=16)
def operating_table(
    model: FlexibleArm, geometry: Geometry, elbow: tuple[float, ...], shoulder: tuple[float, ...]
) -> F64:
    """Rows (len(shoulder), len(elbow), nu + ny), shoulder-major: at each posture the
    holding torques (N m; the compiled statics of
    :mod:`flexarm.control.gravity_compensation`, the sag of
    :meth:`FlexibleArm.equilibrium`) and the measurement at rest there less what the
    law subtracts from the reference (the sensed point's sag, m; rates zero; the
    encoders' offset, rad, for the joint sensor)."""
    sensor = sensor_of(geometry)
    nu, n = model.n_links, model.n_dof
    link, distance, _ = sensor.resolve(model)
    ny = 4 if link >= 0 else 2 * nu
    postures = np.array([(t1, t2) for t1 in shoulder for t2 in elbow], dtype=float)
    q = np.zeros((postures.shape[0], n))
    tau = np.zeros((postures.shape[0], nu))
    scratch = np.zeros(scratch_size(n, nu))
    for k, theta in enumerate(postures):
        holding_torques(theta, model.arrays, scratch, tau[k])
        q[k] = scratch[:n]
    if model.has_flexible_joints:  # the motors ahead of their links by the springs' deflection
        for k, theta in enumerate(postures):
            q[k] = model.equilibrium(theta).q
    y = measure(model, sensor, q, np.zeros_like(q))
    y0 = np.zeros((postures.shape[0], ny))
    if link >= 0:
        levers = lever_lengths(model.link_lengths, link, distance)
        rp = y_point(nu)
        y0[:, :2] = y[:, rp : rp + 2] - rigid_point(levers, postures)[0]
    else:
        y0[:, :nu] = y[:, y_angles(nu) : y_angles(nu) + nu] - postures
    rows = np.concatenate([tau, y0], axis=1).reshape(len(shoulder), len(elbow), nu + ny)
    rows.flags.writeable = False
    return rows
