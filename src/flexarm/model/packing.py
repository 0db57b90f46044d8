"""From arm parameters to the packed arrays: clamped-mass tip loads and :func:`pack`."""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from . import arrays as layout
from .arrays import N_JOINT_COLUMNS, N_LINK_COLUMNS, ArmArrays, pack_arm_arrays
from .beam import BeamModes
from .foreshortening import foreshortening_integrals
from .joints import LinearJoint, NonlinearJoint, RigidJoint
from .link import AnyLink

__all__ = ["ArmParameters", "PackableArm", "outboard_loads", "pack"]

F64 = NDArray[np.float64]


class ArmParameters(Protocol):
    """The parameters and sizes of an arm (:class:`flexarm.FlexibleArm`) that every
    function building its model reads (:func:`pack`,
    :func:`flexarm.model.lagrangian.body_terms`)."""

    @property
    def links(self) -> Sequence[AnyLink]: ...
    @property
    def joints(self) -> Sequence[LinearJoint | NonlinearJoint | RigidJoint] | None: ...
    @property
    def has_flexible_joints(self) -> bool: ...
    @property
    def payload_mass(self) -> float: ...
    @property
    def payload_inertia(self) -> float: ...
    @property
    def rotor_coupling(self) -> bool: ...
    @property
    def n_dof(self) -> int: ...
    @property
    def n_links(self) -> int: ...


class PackableArm(ArmParameters, Protocol):
    """What :func:`pack` and :func:`outboard_loads` read of an arm."""

    @property
    def boundary(self) -> str: ...
    @property
    def joint_friction(self) -> str: ...
    @property
    def geometric_stiffening(self) -> bool: ...
    @property
    def gravity(self) -> tuple[float, float] | None: ...
    @property
    def modes(self) -> tuple[BeamModes, ...]: ...
    @property
    def n_modes(self) -> tuple[int, ...]: ...


def outboard_loads(arm: PackableArm) -> list[tuple[float, float]]:
    """Tip mass (kg) and rotary inertia about the tip (kg m**2) loading each link's
    modes: zero for ``"clamped-free"``; for ``"clamped-mass"`` the link's own tip
    body and everything outboard (links, hub masses and inertias, rotors, tip
    bodies, payload), the chain straight."""
    links = arm.links
    if arm.boundary == "clamped-free":
        return [(0.0, 0.0)] * len(links)
    loads = []
    for i in range(len(links)):
        mass = arm.payload_mass + links[i].tip_mass  # its own tip body, then outboard
        inertia = arm.payload_inertia + links[i].tip_inertia
        d = 0.0  # distance from tip i to the base of the next outboard link
        for k, lk in enumerate(links[i + 1 :], start=i + 1):
            mass += lk.hub_mass + lk.mass + lk.tip_mass
            inertia += lk.hub_mass * d**2 + lk.hub_inertia
            if arm.joints is not None:  # the rotor's own inertia rides on the chain
                jt = arm.joints[k]
                inertia += jt.motor_inertia / jt.gear_ratio**2
            inertia += lk.inertia_behind(d)
            d += lk.length
            inertia += lk.tip_mass * d**2 + lk.tip_inertia
        inertia += arm.payload_mass * d**2
        loads.append((mass, inertia))
    return loads


def pack(arm: PackableArm) -> ArmArrays:
    """``arm`` as :class:`ArmArrays` for the compiled kernels (read-only arrays)."""
    n, N = arm.n_dof, arm.n_links
    start = np.zeros(N + 1, dtype=np.int64)
    start[0] = N
    for i, lk in enumerate(arm.links):
        start[i + 1] = start[i] + lk.n_modes
    link = np.zeros((N, N_LINK_COLUMNS))
    v, w, h, g = (np.zeros(n) for _ in range(4))
    md = np.zeros((n, n))
    k, d = np.zeros(n), np.zeros(n)
    rigid_joints = arm.joints is not None and isinstance(arm.joints[0], RigidJoint)
    for i, (lk, bm) in enumerate(zip(arm.links, arm.modes, strict=True)):
        row = link[i]
        row[: layout.HUB_MASS + 1] = (
            lk.length,
            lk.mass,
            lk.first_moment,
            lk.joint_inertia + lk.hub_inertia,
            lk.hub_mass + (arm.links[i - 1].tip_mass if i > 0 else 0.0),
        )
        if i + 1 < N:  # the last link's tip body is in the payload
            row[layout.TIP_INERTIA] = lk.tip_inertia
        if rigid_joints:
            assert arm.joints is not None
            jt = arm.joints[i]
            row[layout.ROTOR_INERTIA] = jt.motor_inertia
            row[layout.ROTOR_COUPLING] = 1.0 / jt.gear_ratio if arm.rotor_coupling else 0.0
            d[i] = jt.damping
            if jt.friction is not None:
                row[layout.ROTOR_FRICTION] = 1.0
                row[layout.ROTOR_G1 : layout.ROTOR_G1 + 6] = jt.friction.params
        s = slice(start[i], start[i + 1])
        v[s], w[s] = bm.mass_integral, bm.moment_integral
        h[s], g[s] = bm.tip_deflection, bm.tip_slope
        md[s, s] = bm.modal_mass
        k[s] = np.diag(bm.modal_stiffness)
        d[s] = 2.0 * lk.modal_damping * bm.frequencies * np.diag(bm.generalized_mass)
    springs: Sequence[LinearJoint | NonlinearJoint] = (
        () if rigid_joints else arm.joints or ()  # type: ignore[assignment]
    )
    joint = np.zeros((len(springs), N_JOINT_COLUMNS))
    for i, jt in enumerate(springs):
        row = joint[i]
        row[layout.J_A1 : layout.J_ASW + 1] = jt.spring_params
        row[layout.J_INERTIA] = jt.motor_inertia
        row[layout.J_DAMPING] = jt.motor_damping
        row[layout.J_COUPLED] = 1.0 / jt.gear_ratio if arm.rotor_coupling else 0.0
        if jt.friction is not None:
            row[layout.J_HAS_FRICTION] = 1.0
            side = jt.friction_side or arm.joint_friction
            row[layout.J_FRICTION_ON_MOTOR] = float(side == "motor")
            row[layout.J_G1 : layout.J_G1 + 6] = jt.friction.params
        row[layout.J_SPRING_DAMPING] = jt.damping
    shortening = _pack_foreshortening(arm, start) if arm.geometric_stiffening else {}
    return pack_arm_arrays(
        mode_start=start,
        link=link,
        mass_integral=v,
        moment_integral=w,
        tip_deflection=h,
        tip_slope=g,
        modal_mass=md,
        stiffness=k,
        damping=d,
        payload=np.array(
            [
                arm.payload_mass + arm.links[-1].tip_mass,
                arm.payload_inertia + arm.links[-1].tip_inertia,
            ]
        ),
        joint=joint,
        gravity=None if arm.gravity is None else np.array(arm.gravity, dtype=float),
        **shortening,
    )


def _pack_foreshortening(arm: PackableArm, start: NDArray[np.int64]) -> dict[str, F64]:
    """The foreshortening integrals of every link, in the layout of :class:`ArmArrays`."""
    n = arm.n_dof
    k = max(arm.n_modes) if arm.n_modes else 0
    tip, mass, moment = np.zeros((n, n)), np.zeros((n, n)), np.zeros((n, n))
    cubic, quartic = np.zeros((n, k, k)), np.zeros((n, k, k, k))
    for i, bm in enumerate(arm.modes):
        a0, a1 = int(start[i]), int(start[i + 1])
        if a1 == a0:
            continue
        f = foreshortening_integrals(bm)
        s, m = slice(a0, a1), a1 - a0
        tip[s, s], mass[s, s], moment[s, s] = f.tip, f.mass, f.moment
        cubic[s, :m, :m] = f.cubic
        quartic[s, :m, :m, :m] = f.quartic
    return {
        "shortening_tip": tip,
        "shortening_mass": mass,
        "shortening_moment": moment,
        "shortening_cubic": cubic,
        "shortening_quartic": quartic,
    }
