"""Your own control law, by name: ``flexarm simulate --controller my_controller:make``.

A controller factory takes the arm (and, from a scenario file, the ``[controller]``
table's other keys as keyword arguments) and returns a flexarm ``Controller``;
here a ``CompiledController`` around a ``numba.njit`` law, which the simulator
calls from its compiled loop through a C function pointer. The law sees the
measurement ``y`` and the reference ``r`` (layouts in ``flexarm.control.signals``)
and writes the joint torques ``tau`` (N m).

This one is a joint-space PD on the reference's joint angles with strain feedback:
each joint also pushes against its own link's first modal coordinate (a strain
gauge at the link's root would read it), ``tau_i = kp (theta_r - theta)
+ kd (dtheta_r - dtheta) - strain_gain * delta_i``.

Run it from this directory, or through the scenario beside it (the module is found
beside the scenario file)::

    flexarm simulate --controller my_controller:make --duration 1
    flexarm simulate --scenario examples/my_controller.toml
"""

from __future__ import annotations

import numba
import numpy as np

from flexarm.control.controllers import CompiledController
from flexarm.control.signals import r_angles, r_rates, y_angles, y_modes, y_rates

__all__ = ["make"]


@numba.njit(cache=True, nogil=True)
def pd_with_strain_feedback(t, y, r, params, state, tau):
    """``params = [kp, kd, strain_gain, index of link 0's first mode in y's modes, ...]``."""
    n = tau.shape[0]
    ra, rr, ya, yr, ym = r_angles(n), r_rates(n), y_angles(n), y_rates(n), y_modes(n)
    kp, kd, ks = params[0], params[1], params[2]
    for i in range(n):
        tau[i] = kp * (r[ra + i] - y[ya + i]) + kd * (r[rr + i] - y[yr + i])
        first = int(params[3 + i])
        if first >= 0:
            tau[i] -= ks * y[ym + first]


def make(arm, kp=200.0, kd=40.0, strain_gain=0.0):
    """The law for ``arm``: gains ``kp`` (N m/rad), ``kd`` (N m s/rad) and
    ``strain_gain`` (N m per modal unit) on every joint."""
    starts = np.cumsum([0, *arm.n_modes[:-1]])
    first = [float(s) if m > 0 else -1.0 for s, m in zip(starts, arm.n_modes, strict=True)]
    return CompiledController(
        pd_with_strain_feedback,
        params=[float(kp), float(kd), float(strain_gain), *first],
        name="pd+strain",
    )
