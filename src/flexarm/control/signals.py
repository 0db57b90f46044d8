"""The layout of the signal vectors shared by the simulator and the controllers.

A controller sees two plain vectors each control period:

Measurement ``y``, length ``2 N + 4 + n_modes``::

    y[0:N]          collocated angles, rad: joint angles (rigid joints) or motor
                    angles (flexible joints), as the encoders read them
    y[N:2N]         their rates, rad/s
    y[2N:2N+2]      position (x, y) of the sensed point, m: the rigid kinematics of
                    the collocated angles for the joint sensor, the deflected point
                    for a noncollocated sensor (possibly delayed, noisy, quantised)
    y[2N+2:2N+4]    its velocity, m/s
    y[2N+4:]        the links' modal coordinates (what a strain sensor or an
                    estimator would give; the fuzzy law reads link deflections)

Reference ``r``, length ``6 + 2 N``::

    r[0:2]          commanded end-effector position, m
    r[2:4]          velocity, m/s
    r[4:6]          acceleration, m/s**2
    r[6:6+N]        joint angles from inverse kinematics, rad
    r[6+N:6+2N]     joint rates, rad/s
"""

from __future__ import annotations

__all__ = ["R_ACC", "R_POS", "R_VEL", "Y_THETA", "measurement_size", "reference_size"]

Y_THETA = 0
R_POS, R_VEL, R_ACC = 0, 2, 4


def measurement_size(n_links: int, n_modes: int) -> int:
    """Length of ``y`` for ``n_links`` links and ``n_modes`` modal coordinates."""
    return 2 * n_links + 4 + n_modes


def reference_size(n_links: int) -> int:
    """Length of ``r`` for ``n_links`` links."""
    return 6 + 2 * n_links
