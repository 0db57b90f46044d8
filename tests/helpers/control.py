"""Helpers of the tests of references and control: derivatives in time."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

H = 1e-5  # finite-difference step, s


def central_difference(
    fun: Callable[[np.ndarray], np.ndarray], t: np.ndarray, h: float = H
) -> np.ndarray:
    """``d fun / dt`` at ``t`` (s) by the central difference of step ``h`` (s)."""
    return (fun(t + h) - fun(t - h)) / (2 * h)
