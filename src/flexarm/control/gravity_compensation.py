r"""Gravity compensation: the torques that hold the arm's static posture, compiled.

A law designed for the arm in a horizontal plane, run on the arm in a vertical
one (``FlexibleArm(gravity=...)``), is given its weight to carry: a joint PD then
stands off its reference by ``tau_g / K_p`` at rest. :func:`flexarm.simulate` adds
to the law's torque (``gravity_compensation``, on by default for the built-in laws
when the arm has gravity) the joint torques that hold the measured posture at
rest,

.. math:: \tau_c = \tau_{eq}(\theta_m) = \frac{\partial V}{\partial \theta}
          (\theta_m, \delta_{eq}), \qquad K \delta_{eq} = -\frac{\partial V}
          {\partial \delta}(\theta_m, \delta_{eq}),

the holding torques of :meth:`flexarm.FlexibleArm.equilibrium` at the collocated
angles ``theta_m`` the encoders read, evaluated at every control instant:

* The static posture, not the rigid one: a flexible link sags, which moves the
  outboard masses and turns the outboard links by the tip slope; on the paper's
  4.5 m links under 9.81 m/s**2 the holding torques differ from the straight
  links' by up to about 10 % (5-7 N m away from the horizontal posture). With the
  sag in it, a joint PD comes to rest on its reference exactly.
* At the measured angles, not the reference ones: the law of Takegaki and Arimoto
  (PD plus gravity at the measured configuration, asymptotically stable for any
  positive gains on a rigid arm) and of De Luca, Siciliano and Zollo's on-line
  compensation on elastic robots. It removes gravity's stiffness from the loop
  (the softening of a standing posture, the stiffening of a hanging one), so the
  joints' loop about any posture has the horizontal arm's gains; evaluated at the
  reference it would hold the posture all the same but leave gravity's stiffness
  in the loop.
* The sag by a fixed-point iteration ``delta <- K^-1 f_g(theta, delta)`` (one
  evaluation of the compiled gravity forces per pass, converging as long as the
  posture is far from a link's buckling load; on the paper's arm a pass gains about
  a decimal digit), started from the sag extrapolated linearly from the last two
  instants, whose error is second order in the posture's change per period: 3.8
  passes an instant on the paper's arm tracking the square at 5 kHz, against 6.6
  from the previous instant's sag alone.
* With flexible joints the measured angles are the motors': the compensation is
  that of the link posture at the motor angles, wrong by the springs' static
  deflection (``tau / k``: a few milliradians on a stiff spring).

The compensation uses the simulated arm's own model (the law is designed for it);
a run of an arm without gravity never calls it, bit for bit the result it had.
"""

from __future__ import annotations

import numba as nb
import numpy as np
from numpy.typing import NDArray

from .._compile import njit_runtime_free
from ..model.arrays import ArmArrays
from ..model.dynamics._gravity import (
    gravity_forces,
    gravity_forces_two_links_one_mode,
    has_gravity,
)
from ..model.dynamics._two_links import is_two_links_one_mode

__all__ = ["MAX_PASSES", "TOLERANCE", "holding_torques", "scratch_size"]

F64 = NDArray[np.float64]

MAX_PASSES = 50
"""Fixed-point passes at the most per control instant (the sag then in use if
they do not converge: a posture close to a link's buckling load)."""

TOLERANCE = 1e-12
"""The passes stop when no modal coordinate changes by more than this times
(1 + the largest of them)."""


def scratch_size(n_dof: int, n_links: int) -> int:
    """Length of the scratch vector :func:`holding_torques` needs (its layout: the
    posture ``q`` with the last sag found, shape (n_dof,), the forces, shape
    (n_dof,), the sag found the call before, shape (n_dof,), and the calls made
    (counted up to 2); zeros before the first call)."""
    return 3 * n_dof + 1


@njit_runtime_free(cache=True, nogil=True)
def holding_torques(
    theta: F64, arrays: ArmArrays, scratch: F64, tau: F64
) -> int:  # pragma: no cover - compiled
    """Write into ``tau`` the joint torques that hold the arm at rest with joint
    angles ``theta`` against gravity (module docstring); return the passes made.

    Parameters
    ----------
    theta : ndarray, shape (n_links,)
        Joint angles, rad.
    arrays : ArmArrays
        The arm.
    scratch : ndarray, shape (3 n_dof + 1,)
        :func:`scratch_size`; it keeps the last two sags between calls (the next
        call starts from their linear extrapolation, or from the one sag after a
        single call; zeros: straight links, no call made).
    tau : ndarray, shape (n_links,)
        Written, N m (zeros without gravity).
    """
    n_links = arrays.link.shape[0]
    n = (scratch.shape[0] - 1) // 3
    q, rhs, before = scratch[:n], scratch[n : 2 * n], scratch[2 * n : 3 * n]
    for i in range(n_links):
        q[i] = theta[i]
        tau[i] = 0.0
    if not has_gravity(arrays):
        return 0
    m0, m1 = n_links, arrays.mode_start[n_links]
    k = arrays.stiffness
    extrapolate = scratch[3 * n] >= 2.0
    for g in range(m0, m1):  # the start: the last two sags extrapolated
        last = q[g]
        if extrapolate:
            q[g] = 2.0 * last - before[g]
        before[g] = last
    if not extrapolate:
        scratch[3 * n] += 1.0
    if is_two_links_one_mode(arrays):  # the paper's structure: the same passes in scalars
        return _two_links_one_mode(q, arrays, tau)
    passes = 0
    for _ in range(MAX_PASSES if m1 > m0 else 0):
        for c in range(n):
            rhs[c] = 0.0
        gravity_forces(q, arrays, rhs)
        passes += 1
        change, size = 0.0, 0.0
        for g in range(m0, m1):
            new = rhs[g] / k[g] if k[g] > 0.0 else 0.0
            change = max(change, abs(new - q[g]))
            size = max(size, abs(new))
            q[g] = new
        if change <= TOLERANCE * (1.0 + size):
            break
    for c in range(n):
        rhs[c] = 0.0
    gravity_forces(q, arrays, rhs)
    for i in range(n_links):
        tau[i] = -rhs[i]
    return passes


@nb.njit(cache=True, nogil=True, inline="always")
def _two_links_one_mode(q: F64, arrays: ArmArrays, tau: F64) -> int:  # pragma: no cover
    """:func:`holding_torques`' passes for two links of one mode each without geometric
    stiffening (``q = (theta1, theta2, delta1, delta2)``, the sag's start in it), on
    the scalar gravity forces of the two-link kernel; the sag found written back."""
    k2, k3 = arrays.stiffness[2], arrays.stiffness[3]
    a1, a2, d1, d2 = q[0], q[1], q[2], q[3]
    passes = 0
    for _ in range(MAX_PASSES):
        _, _, f2, f3 = gravity_forces_two_links_one_mode(a1, a2, d1, d2, arrays)
        passes += 1
        n1 = f2 / k2 if k2 > 0.0 else 0.0
        n2 = f3 / k3 if k3 > 0.0 else 0.0
        change = max(abs(n1 - d1), abs(n2 - d2))
        size = max(abs(n1), abs(n2))
        d1, d2 = n1, n2
        if change <= TOLERANCE * (1.0 + size):
            break
    f0, f1, _, _ = gravity_forces_two_links_one_mode(a1, a2, d1, d2, arrays)
    q[2], q[3] = d1, d2
    tau[0], tau[1] = -f0, -f1
    return passes
