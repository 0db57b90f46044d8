"""Natural frequencies and damping ratios of an arm, from its linearised poles.

About a configuration at rest the arm is ``M qdd + D qd + K q = B tau``
(:attr:`FlexibleArm.damping_matrix`: modal damping and the joints' viscous
damping; friction's viscous part where the joint's friction has one). Its poles
are the eigenvalues of ``[[0, I], [-M^-1 K, -M^-1 D]]``; each pair of complex
poles ``-zeta w +- i w sqrt(1 - zeta^2)`` is a mode of natural frequency ``w`` and
damping ratio ``zeta``, an overdamped mode a pair of real poles. With the
actuated coordinates locked (infinitely stiff servos, the default) this is what a
link rings at when its hub is held; with them free (``tau = 0``) the rigid-body
motions are left out.

Examples
--------
>>> import flexarm as fa
>>> arm = fa.FlexibleArm.paper()
>>> modes = damped_modes(arm)
>>> modes.frequencies.round(3).tolist() == arm.natural_frequencies().round(3).tolist()
True
>>> damped_modes(fa.FlexibleArm([fa.Link(4.5, 1676.0, 0.335, n_modes=1,
...                                      modal_damping=0.05)])).damping.round(3).tolist()
[0.05]
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_option
from .arm import FlexibleArm

__all__ = ["DampedModes", "damped_modes"]

F64 = NDArray[np.float64]


class DampedModes(NamedTuple):
    """Modes of the linearised arm, slowest first.

    Attributes
    ----------
    frequencies : ndarray
        Natural frequencies ``w``, rad/s.
    damping : ndarray
        Damping ratios ``zeta`` (>= 1 for an overdamped mode).
    damped_frequencies : ndarray
        ``w sqrt(1 - zeta^2)``, rad/s (0 for an overdamped mode): what a free
        response rings at.
    """

    frequencies: F64
    damping: F64
    damped_frequencies: F64

    @property
    def frequencies_hz(self) -> F64:
        """Natural frequencies, Hz."""
        return self.frequencies / (2 * np.pi)


def damped_modes(
    arm: FlexibleArm, q: ArrayLike | None = None, joints: str = "locked"
) -> DampedModes:
    """The arm's modes with damping, linearised at rest about ``q`` (module docstring).

    Parameters
    ----------
    arm : FlexibleArm
    q : array_like, shape (n_dof,), optional
        Configuration (default straight, all zeros).
    joints : {"locked", "free"}
        Actuated coordinates held fixed, or unactuated (rigid-body motions left out).
    """
    from scipy.linalg import eig

    check_option(joints, "joints", "damped_modes", ("locked", "free"))
    n = arm.n_dof
    q0 = np.zeros(n) if q is None else np.asarray(q, dtype=float)
    M = np.asarray(arm.mass_matrix(q0).real, dtype=np.float64)
    K = np.asarray(arm.stiffness_matrix, dtype=np.float64)
    D = np.asarray(arm.damping_matrix, dtype=np.float64)
    keep = np.ones(n, dtype=bool)
    if joints == "locked":
        keep[arm.actuated_slice] = False
    M, K, D = (A[np.ix_(keep, keep)] for A in (M, K, D))
    m = M.shape[0]
    if m == 0:
        empty = np.zeros(0)
        return DampedModes(frequencies=empty, damping=empty, damped_frequencies=empty)
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-Minv @ K, -Minv @ D]])
    poles = eig(A, right=False)
    scale = max(1.0, float(np.max(np.abs(poles))))
    rigid = np.abs(poles) <= 1e-9 * scale
    poles = poles[~rigid]
    complex_ = poles[poles.imag > 1e-12 * scale]
    w_c = np.abs(complex_)
    z_c = -complex_.real / w_c
    real = np.sort(poles[np.abs(poles.imag) <= 1e-12 * scale].real)  # overdamped pairs
    w_r, z_r = [], []
    for a, b in zip(real[0::2], real[1::2], strict=False):
        w = float(np.sqrt(a * b))  # poles -zeta w +- w sqrt(zeta^2 - 1)
        w_r.append(w)
        z_r.append(float(-(a + b) / (2 * w)))
    w_all = np.r_[w_c, w_r]
    z_all = np.r_[z_c, z_r]
    order = np.argsort(w_all)
    w_all, z_all = w_all[order], z_all[order]
    wd = w_all * np.sqrt(np.clip(1.0 - z_all**2, 0.0, None))
    return DampedModes(frequencies=w_all, damping=z_all, damped_frequencies=wd)
