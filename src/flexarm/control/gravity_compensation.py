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
  posture is far from a link's buckling load), started from the previous instant's
  sag: one or two passes a period when the arm moves smoothly.
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

from ..model.arrays import ArmArrays
from ..model.dynamics._gravity import gravity_forces, has_gravity

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
    posture ``q`` with the last sag found, shape (n_dof,), then the forces,
    shape (n_dof,))."""
    return 2 * n_dof


@nb.njit(cache=True, nogil=True)
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
    scratch : ndarray, shape (2 n_dof,)
        :func:`scratch_size`; its first ``n_dof`` entries keep the sag between calls
        (the next call starts from it; zeros: straight links).
    tau : ndarray, shape (n_links,)
        Written, N m (zeros without gravity).
    """
    n_links = arrays.link.shape[0]
    n = scratch.shape[0] // 2
    q, rhs = scratch[:n], scratch[n:]
    for i in range(n_links):
        q[i] = theta[i]
        tau[i] = 0.0
    if not has_gravity(arrays):
        return 0
    m0, m1 = n_links, arrays.mode_start[n_links]
    k = arrays.stiffness
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
