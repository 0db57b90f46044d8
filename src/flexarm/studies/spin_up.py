"""The spin-up benchmark of Kane, Ryan & Banerjee: :func:`spin_up`.

T. R. Kane, R. R. Ryan and A. K. Banerjee, "Dynamics of a cantilever beam
attached to a moving base", J. Guidance, Control and Dynamics 10(2), 1987: a
uniform beam (L = 10 m, EI = 1.4e4 N m**2, rho A = 1.2 kg/m) clamped to a hub
whose angle is prescribed,

    theta(t) = (Omega / T) [t**2 / 2 + (T / 2 pi)**2 (cos(2 pi t / T) - 1)],  t < T,
    theta(t) = Omega t - Omega T / 2,                                          t >= T,

with T = 15 s and Omega = 6 rad/s (the hub ends faster than the beam's first
bending frequency, 3.80 rad/s). A model without geometric stiffening predicts
a tip deflection of -0.52 m at 5 s, -7.4 m at 9 s, -72 m at 10 s and -1.9 km at
11 s; the beam stays within 0.6 m. flexarm drives the hub by prescribed joint
motion — the joint angle is imposed exactly
(:func:`flexarm.sim.prescribed.simulate_prescribed`), not tracked by
a servo — and with geometric stiffening agrees with Exudyn's geometrically
exact ANCF beam within 0.4 % of the peak deflection at Omega = 6 rad/s and
0.05 % at 2 rad/s (tests/test_exudyn_oracle.py).
"""

from __future__ import annotations

import numpy as np

from .._types import F64
from .._validation import check_real
from ..errors import InvalidValueError
from ..model.arm import FlexibleArm
from ..model.link import Link
from ..sim.prescribed import JointMotion, simulate_prescribed
from ..sim.results import SimulationResult

__all__ = ["KANE_LINK", "kane_motion", "spin_up"]


KANE_LINK = Link(10.0, 1.4e4, 1.2, n_modes=3)
"""The beam of Kane, Ryan & Banerjee (1987): L (m), EI (N m**2), rho A (kg/m)."""


def kane_motion(omega: float = 6.0, ramp: float = 15.0) -> JointMotion:
    """The hub's prescribed angle (rad), rate and acceleration as functions of time.

    Parameters
    ----------
    omega : float
        Final spin rate, rad/s (> 0).
    ramp : float
        Spin-up time ``T``, s (> 0).
    """
    w = check_real(omega, "omega", "kane_motion", positive=True)
    T = check_real(ramp, "ramp", "kane_motion", positive=True)
    c = T / (2 * np.pi)

    def motion(t: F64) -> tuple[F64, F64, F64]:
        t = np.asarray(t, dtype=float)
        on = t < T
        theta = np.where(on, w / T * (t**2 / 2 + c**2 * (np.cos(t / c) - 1)), w * (t - T / 2))
        rate = np.where(on, w / T * (t - c * np.sin(t / c)), w)
        acc = np.where(on, w / T * (1 - np.cos(t / c)), 0.0)
        return theta, rate, acc

    return motion


def spin_up(
    omega: float = 6.0,
    *,
    arm: FlexibleArm | None = None,
    ramp: float = 15.0,
    duration: float = 20.0,
    dt: float = 0.01,
    substeps: int = 5,
    geometric_stiffening: bool | None = None,
) -> SimulationResult:
    """Kane's spin-up of a one-link arm by prescribed hub motion.

    Parameters
    ----------
    omega : float
        Final spin rate, rad/s.
    arm : FlexibleArm, optional
        A one-link arm (default: :data:`KANE_LINK` with FlexibleArm's defaults).
    geometric_stiffening : bool, optional
        For the default arm: with (the default) or without geometric stiffening.
    ramp, duration : float
        Spin-up time and simulated time, s.
    dt : float
        Output interval, s; ``substeps`` RK4 steps each.

    Returns
    -------
    SimulationResult
        ``link_deflections[:, 0]`` is the tip deflection in the hub's frame, m.

    Raises
    ------
    SimulationError
        If the beam diverges (a model without geometric stiffening above
        ``omega`` = 3.8 rad/s).
    """
    if arm is None:
        stiff = True if geometric_stiffening is None else geometric_stiffening
        arm = FlexibleArm([KANE_LINK], geometric_stiffening=stiff)
    elif geometric_stiffening is not None:
        raise InvalidValueError(
            "The 'arm' parameter of spin_up comes with its own geometric_stiffening. "
            f"Got geometric_stiffening={geometric_stiffening!r} as well instead."
        )
    t = np.linspace(0.0, duration, round(duration / dt) + 1)
    return simulate_prescribed(
        arm, t, kane_motion(omega, ramp), substeps=substeps, max_deflection=arm.links[0].length
    )
