"""The checks that turn a PD law's gains into arrays: per-joint vectors and 2 x 2
operational-space matrices."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array
from ..errors import InvalidValueError

__all__ = ["gain_matrix", "gain_vector"]


def gain_vector(value: ArrayLike, name: str, owner: str, n: int) -> NDArray[np.float64]:
    """A scalar or ``n`` non-negative gains as a vector of shape (n,) (joint-space PD)."""
    g = check_array(value, name, owner, real=True)
    if g.ndim == 0:
        g = np.full(n, float(g))
    if g.shape != (n,):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be a scalar or of shape ({n},). "
            f"Got shape {g.shape} instead."
        )
    if np.any(g < 0):
        raise InvalidValueError(f"The '{name}' parameter of {owner} must be >= 0. Got {g} instead.")
    return g


def gain_matrix(value: ArrayLike, name: str, owner: str) -> NDArray[np.float64]:
    """A scalar, a diagonal (2,) or a (2, 2) gain as a positive semidefinite (2, 2) matrix
    (operational-space PD)."""
    g = check_array(value, name, owner, real=True)
    if g.ndim == 0:
        g = float(g) * np.eye(2)
    elif g.shape == (2,):
        g = np.diag(g)
    if g.shape != (2, 2):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be a scalar, of shape (2,) or (2, 2). "
            f"Got shape {g.shape} instead."
        )
    lowest = float(np.linalg.eigvalsh(0.5 * g + 0.5 * g.T).min())  # no overflow near 1e308
    if lowest < 0.0:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be positive semidefinite (a gain that "
            f"pushes away from the reference is not a PD law). Got {value!r}, whose "
            f"symmetric part has the eigenvalue {lowest:.6g}, instead."
        )
    return g
