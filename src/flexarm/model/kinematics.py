r"""Planar kinematics of the arm, as functions of plain arrays.

Rigid kinematics (what a joint encoder implies, and what the paper's controllers
use, eqs. 9–10) and the deflected kinematics of a point on a flexible link
(:meth:`flexarm.FlexibleArm.point_position`). Angles in rad, lengths in m.

A point ``distance`` along link ``link`` (0-based) of a rigid chain with absolute
link angles ``phi_i = theta_0 + ... + theta_i`` is

.. math:: p = \sum_{i < link} L_i (\cos\phi_i, \sin\phi_i)
          + d (\cos\phi_{link}, \sin\phi_{link}),

so its Jacobian is that of the end effector with the *lever lengths*
``(L_0, ..., L_{link-1}, d, 0, ...)`` (:func:`lever_lengths`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_option, check_real
from ..errors import InvalidValueError
from .arrays import LEN, ArmArrays
from .beam import BeamModes
from .foreshortening import shortening_matrix

__all__ = [
    "RigidKinematics",
    "deflected_point",
    "lever_lengths",
    "rigid_jacobian",
    "rigid_point",
    "two_link_inverse_kinematics",
]

F64 = NDArray[np.float64]


def lever_lengths(lengths: ArrayLike, link: int, distance: float) -> F64:
    """Lever lengths of the point ``distance`` along ``link``: ``L_0, ..., L_{link-1},
    distance, 0, ...`` (shape ``(n_links,)``, m)."""
    lengths = np.asarray(lengths, dtype=float)
    out = np.zeros_like(lengths)
    out[:link] = lengths[:link]
    out[link] = distance
    return out


def rigid_point(
    levers: ArrayLike, theta: ArrayLike, dtheta: ArrayLike | None = None
) -> tuple[F64, F64 | None]:
    """Position and velocity of a point of a rigid chain.

    Parameters
    ----------
    levers : array_like, shape (n_links,)
        Lever lengths of the point (:func:`lever_lengths`; the link lengths for
        the end effector), m.
    theta : array_like, shape (..., n_links)
        Joint angles, rad.
    dtheta : array_like, shape (..., n_links), optional
        Joint rates, rad/s.

    Returns
    -------
    position : ndarray, shape (..., 2)
        m.
    velocity : ndarray, shape (..., 2) or None
        m/s (None without ``dtheta``).
    """
    levers = np.asarray(levers, dtype=float)
    phi = np.cumsum(np.asarray(theta, dtype=float), axis=-1)
    c, s = np.cos(phi), np.sin(phi)
    position = np.stack([c @ levers, s @ levers], axis=-1)
    if dtheta is None:
        return position, None
    w = np.cumsum(np.asarray(dtheta, dtype=float), axis=-1) * levers
    velocity = np.stack([-np.sum(s * w, axis=-1), np.sum(c * w, axis=-1)], axis=-1)
    return position, velocity


def rigid_jacobian(levers: ArrayLike, theta: ArrayLike) -> F64:
    """Jacobian ``d(x, y)/d theta`` of a point of a rigid chain, m/rad.

    Parameters
    ----------
    levers : array_like, shape (n_links,)
        Lever lengths of the point (:func:`lever_lengths`), m.
    theta : array_like, shape (..., n_links)
        Joint angles, rad.

    Returns
    -------
    ndarray, shape (..., 2, n_links)
        Column ``k`` is ``sum_{i >= k} levers_i (-sin phi_i, cos phi_i)``.
    """
    levers = np.asarray(levers, dtype=float)
    phi = np.cumsum(np.asarray(theta, dtype=float), axis=-1)
    cx = np.flip(np.cumsum(np.flip(-levers * np.sin(phi), -1), -1), -1)
    cy = np.flip(np.cumsum(np.flip(levers * np.cos(phi), -1), -1), -1)
    return np.stack([cx, cy], axis=-2)


def two_link_inverse_kinematics(l1: float, l2: float, position: F64, elbow: str, owner: str) -> F64:
    """Joint angles of a rigid two-link arm with its tip at ``position`` (m, shape
    ``(..., 2)``); ``elbow`` ``"positive"`` or ``"negative"`` is the sign of
    ``theta_2``. Returns shape ``(..., 2)``, ``theta_1`` wrapped to ``[-pi, pi)``.

    Raises InvalidValueError naming ``owner`` for a target out of reach.
    """
    x, y = position[..., 0], position[..., 1]
    r2 = x**2 + y**2
    c2 = (r2 - l1**2 - l2**2) / (2 * l1 * l2)
    tol = 1e-12
    bad = (c2 > 1 + tol) | (c2 < -1 - tol)
    if np.any(bad):
        r = np.sqrt(np.atleast_1d(r2)[np.atleast_1d(bad)][0])
        raise InvalidValueError(
            f"The 'position' parameter of {owner} must be reachable, at a distance in "
            f"[{abs(l1 - l2)}, {l1 + l2}] m from the base. Got a target at {r} m "
            f"({int(np.sum(bad))} unreachable)."
        )
    c2 = np.clip(c2, -1.0, 1.0)
    s2 = np.sqrt(1.0 - c2**2) * (1.0 if elbow == "positive" else -1.0)
    t2 = np.arctan2(s2, c2)
    t1 = np.arctan2(y, x) - np.arctan2(l2 * s2, l1 + l2 * c2)
    t1 = (t1 + math.pi) % (2 * math.pi) - math.pi
    return np.stack([t1, t2], axis=-1)


def deflected_point(
    arrays: ArmArrays,
    phi: F64,
    q: F64,
    link: int,
    distance: float,
    shortening: F64 | None = None,
) -> F64:
    """Position of the point ``distance`` along ``link`` with the links' deflection.

    Parameters
    ----------
    arrays : ArmArrays
        The packed arm (link lengths, tip deflections and slopes of the modes,
        foreshortening at the tips).
    phi : ndarray, shape (n_modes of ``link``,)
        ``link``'s mode shapes at ``distance``.
    q : ndarray, shape (m, n_dof)
        Configurations.
    link : int
        0-based link index.
    distance : float
        Distance along the undeformed link from its joint, m.
    shortening : ndarray, shape (n_modes of ``link``, n_modes of ``link``), optional
        ``S(distance)`` (:func:`flexarm.model.foreshortening.shortening_matrix`):
        the point's own foreshortening with geometric stiffening.

    Returns
    -------
    ndarray, shape (m, 2)
        ``(x, y)`` in m, base frame. Joint ``i`` turns link ``i`` relative to the
        deflected tip of link ``i - 1``: the tip slopes add to the angles. With
        geometric stiffening (``arrays`` holds the foreshortening) a point at
        ``x`` along a link sits at ``x - u(x)`` along its clamped axis.
    """
    ms = arrays.mode_start
    stiff = arrays.shortening_quartic.shape[1] > 0
    pos = np.zeros((q.shape[0], 2))
    alpha = np.zeros(q.shape[0])
    for i in range(link + 1):
        s = slice(int(ms[i]), int(ms[i + 1]))
        alpha = alpha + q[:, i]
        d = q[:, s]
        if i < link:
            x, w = arrays.link[i, LEN], d @ arrays.tip_deflection[s]
            S = arrays.shortening_tip[s, s]
        else:
            x, w = distance, d @ phi
            S = shortening if shortening is not None else np.zeros((d.shape[1],) * 2)
        if stiff:
            x = x - 0.5 * np.einsum("mj,jk,mk->m", d, S, d)
        c, sn = np.cos(alpha), np.sin(alpha)
        pos += np.column_stack([x * c - w * sn, x * sn + w * c])
        alpha = alpha + d @ arrays.tip_slope[s]
    return pos


def point_position_reference(
    modes: BeamModes, arrays: ArmArrays, q: NDArray[Any], link: int, distance: float
) -> NDArray[Any]:
    """The NumPy reference of :meth:`flexarm.FlexibleArm.point_position` (arguments
    checked; ``modes`` those of ``link``; ``q`` real or complex, shape (n_dof,) or
    (m, n_dof))."""
    phi = modes.shape(distance)[:, 0]
    S = shortening_matrix(modes, distance)[:, :, 0]
    pos = deflected_point(arrays, phi, np.atleast_2d(q), link, distance, S)
    return pos[0] if q.ndim == 1 else pos


class RigidKinematics:
    """The rigid-link kinematics of an arm from its link lengths: what encoders
    imply and the paper's controllers use (eqs. 9–10). A base of
    :class:`flexarm.FlexibleArm`, which supplies ``n_links`` and ``link_lengths``."""

    _owner = "FlexibleArm"

    @property
    def n_links(self) -> int:
        raise NotImplementedError

    @property
    def link_lengths(self) -> F64:
        """Link lengths, m, shape ``(n_links,)``."""
        raise NotImplementedError

    def _check_link(self, link: int) -> int:
        """``link``, a 0-based link index, checked."""
        link = check_int(link, "link", self._owner, minimum=0)
        if link >= self.n_links:
            raise InvalidValueError(
                f"The 'link' parameter of {self._owner} must be < {self.n_links} (0-based). "
                f"Got {link} instead."
            )
        return link

    def _check_point(self, link: int, distance: float) -> tuple[int, float]:
        """``link`` (0-based) and ``distance`` (m, in ``[0, L]``) checked."""
        link = self._check_link(link)
        length = float(self.link_lengths[link])
        distance = check_real(distance, "distance", self._owner)
        if not 0.0 <= distance <= length:
            raise InvalidValueError(
                f"The 'distance' parameter of {self._owner} must lie in [0, {length}] for "
                f"link {link}. Got {distance} instead."
            )
        return link, distance

    def _check_theta(self, theta: ArrayLike) -> NDArray[np.float64]:
        arr = check_array(theta, "theta", self._owner)
        if arr.ndim not in (1, 2) or arr.shape[-1] != self.n_links:
            raise InvalidValueError(
                f"The 'theta' parameter of {self._owner} must be of shape ({self.n_links},) or "
                f"(m, {self.n_links}). Got shape {arr.shape} instead."
            )
        return arr

    def forward_kinematics(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Rigid-link tip position from joint angles (deflections ignored).

        Parameters
        ----------
        theta : array_like, shape (n_links,) or (m, n_links)
            Joint angles, rad.

        Returns
        -------
        ndarray, shape (2,) or (m, 2)
            ``x = sum L_i cos(theta_1 + ... + theta_i)``, likewise ``y``; m.
        """
        return rigid_point(self.link_lengths, self._check_theta(theta))[0]

    def jacobian(self, theta: ArrayLike) -> NDArray[np.float64]:
        """Rigid-link Jacobian ``d(x, y)/d theta``, shape ``(2, n_links)`` or
        ``(m, 2, n_links)``, m/rad."""
        return rigid_jacobian(self.link_lengths, self._check_theta(theta))

    def inverse_kinematics(
        self, position: ArrayLike, elbow: str = "positive"
    ) -> NDArray[np.float64]:
        """Joint angles of a two-link arm (rigid links) that put the tip at ``position``.

        Parameters
        ----------
        position : array_like, shape (2,) or (m, 2)
            Target ``(x, y)`` in m.
        elbow : {"positive", "negative"}
            The branch: the sign of ``theta_2``.

        Returns
        -------
        ndarray, shape (2,) or (m, 2)
            ``(theta_1, theta_2)`` in rad, ``theta_2`` in ``[0, pi]`` or ``[-pi, 0]``.

        Raises
        ------
        ValueError
            If the arm does not have two links or a target is out of reach.
        """
        if self.n_links != 2:
            raise InvalidValueError(
                f"inverse_kinematics needs a two-link arm. Got {self.n_links} links instead."
            )
        check_option(elbow, "elbow", self._owner, ("positive", "negative"))
        p = check_array(position, "position", self._owner)
        if p.ndim not in (1, 2) or p.shape[-1] != 2:
            raise InvalidValueError(
                f"The 'position' parameter of {self._owner} must be of shape (2,) or (m, 2). "
                f"Got shape {p.shape} instead."
            )
        l1, l2 = float(self.link_lengths[0]), float(self.link_lengths[1])
        return two_link_inverse_kinematics(l1, l2, p, elbow, self._owner)
