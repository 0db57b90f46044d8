"""The layout of the signal vectors a controller sees: the one definition.

Each control period a controller gets two plain vectors, for an arm of ``N``
links with ``M`` modal coordinates in all:

Measurement ``y``, length :func:`measurement_size` ``= 2 N + 4 + M``::

    y[y_angles(N):+N]        collocated angles, rad: joint angles (rigid joints) or
                             motor angles (flexible joints), as the encoders read them
    y[y_rates(N):+N]         their rates, rad/s
    y[y_point(N):+2]         position (x, y) of the sensed point, m: rigid kinematics
                             of the collocated angles for the joint sensor, the sensed
                             point for a point sensor (possibly delayed, noisy, quantised)
    y[y_point_rate(N):+2]    its velocity, m/s
    y[y_modes(N):+M]         the links' modal coordinates (what a strain sensor or an
                             estimator would give; the fuzzy law reads link deflections)

Reference ``r``, length :func:`reference_size` ``= 6 + 4 N``::

    r[r_position(N):+2]      commanded position of the controlled point, m
    r[r_velocity(N):+2]      velocity, m/s
    r[r_acceleration(N):+2]  acceleration, m/s**2
    r[r_angles(N):+N]        joint angles from inverse kinematics, rad
    r[r_rates(N):+N]         joint rates, rad/s
    r[r_angle_accelerations(N):+N]  joint accelerations, rad/s**2
    r[r_feedforward(N):+N]   feedforward joint torques, N m (the rigid inverse
                             dynamics of the reference; zero unless asked for).
                             The simulator adds them to the law's output.

Every module and every compiled function that reads or writes these vectors
uses the offset functions below (plain Python functions that Numba compiles
inline where a compiled function calls them), so no offset is written twice.
"""

from __future__ import annotations

from numba.extending import register_jitable

__all__ = [
    "measurement_size",
    "r_acceleration",
    "r_angle_accelerations",
    "r_angles",
    "r_feedforward",
    "r_position",
    "r_rates",
    "r_velocity",
    "reference_size",
    "y_angles",
    "y_modes",
    "y_point",
    "y_point_rate",
    "y_rates",
]


@register_jitable
def y_angles(n_links: int) -> int:
    """Offset of the collocated angles in ``y``."""
    return 0


@register_jitable
def y_rates(n_links: int) -> int:
    """Offset of the collocated rates in ``y``."""
    return n_links


@register_jitable
def y_point(n_links: int) -> int:
    """Offset of the sensed point's position (x, y) in ``y``."""
    return 2 * n_links


@register_jitable
def y_point_rate(n_links: int) -> int:
    """Offset of the sensed point's velocity in ``y``."""
    return 2 * n_links + 2


@register_jitable
def y_modes(n_links: int) -> int:
    """Offset of the modal coordinates in ``y``."""
    return 2 * n_links + 4


@register_jitable
def measurement_size(n_links: int, n_modes: int) -> int:
    """Length of ``y`` for ``n_links`` links and ``n_modes`` modal coordinates."""
    return y_modes(n_links) + n_modes


@register_jitable
def r_position(n_links: int) -> int:
    """Offset of the commanded position in ``r``."""
    return 0


@register_jitable
def r_velocity(n_links: int) -> int:
    """Offset of the commanded velocity in ``r``."""
    return 2


@register_jitable
def r_acceleration(n_links: int) -> int:
    """Offset of the commanded acceleration in ``r``."""
    return 4


@register_jitable
def r_angles(n_links: int) -> int:
    """Offset of the joint-angle references in ``r``."""
    return 6


@register_jitable
def r_rates(n_links: int) -> int:
    """Offset of the joint-rate references in ``r``."""
    return 6 + n_links


@register_jitable
def r_angle_accelerations(n_links: int) -> int:
    """Offset of the joint-acceleration references in ``r``."""
    return 6 + 2 * n_links


@register_jitable
def r_feedforward(n_links: int) -> int:
    """Offset of the feedforward torques in ``r``."""
    return 6 + 3 * n_links


@register_jitable
def reference_size(n_links: int) -> int:
    """Length of ``r`` for ``n_links`` links."""
    return r_feedforward(n_links) + n_links
