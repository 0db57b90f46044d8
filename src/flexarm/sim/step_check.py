"""The longest RK4 step an arm's free dynamics can take: what an open-loop run checks.

Classical RK4 advances ``x' = A x`` by ``R(h A)`` with ``R(z) = 1 + z + z^2/2 +
z^3/6 + z^4/24``: stable only where ``|R(h lambda)| <= 1`` for every eigenvalue
``lambda`` of ``A`` (on the negative real axis ``h |lambda| <= 2.785``, on the
imaginary axis ``<= 2.828``). A stiff joint, a high mode or a steep friction law
puts an eigenvalue far out, and a step beyond the bound diverges at once ("diverged
at t = 0.0"). :func:`stable_step` linearises the arm about a state at rest
(``M qdd + D qd + K q = 0``, with the joints' friction linearised at zero speed)
and finds the longest stable step by bisection; :func:`check_substeps` refuses a
step beyond it with the substeps that work, or chooses them.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import UnstableStepError
from ..model.arm import FlexibleArm
from ..model.plant import Plant

__all__ = ["MARGIN", "check_substeps", "rk4_growth", "stable_step"]

F64 = NDArray[np.float64]

MARGIN = 0.9
"""The fraction of the longest stable step a chosen step may take."""


def rk4_growth(z: NDArray[np.complex128] | NDArray[np.float64]) -> NDArray[np.float64]:
    """``|R(z)|``, the growth of RK4 over one step of ``x' = lambda x`` at ``z = h lambda``."""
    r = 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    return np.asarray(np.abs(r), dtype=np.float64)


def _friction_slope(friction: object) -> float:
    """A friction law's slope at zero speed (N m s/rad)."""
    if friction is None:
        return 0.0
    g = [float(getattr(friction, f"g{i}")) for i in range(1, 7)]
    return g[0] * (g[1] - g[2]) + g[3] * g[4] + g[5]


def _linear_matrices(arm: FlexibleArm, q: F64) -> tuple[F64, F64, F64]:
    M = np.asarray(arm.mass_matrix(q).real, dtype=np.float64)
    K = np.asarray(arm.stiffness_matrix, dtype=np.float64)
    D = np.array(arm.damping_matrix, dtype=np.float64)
    if arm.joints is not None:
        for joint, row in zip(arm.joints, arm.friction_coordinates, strict=True):
            D[row, row] += _friction_slope(getattr(joint, "friction", None))
    return M, K, D


def stable_step(
    arm: Plant, q: ArrayLike | None = None, free: NDArray[np.bool_] | None = None
) -> float:
    """The longest RK4 step (s) at which the arm's dynamics linearised at rest about
    ``q`` (default straight) are stable; inf when nothing limits it.

    Parameters
    ----------
    arm : FlexibleArm
    q : array_like, shape (n_dof,), optional
    free : ndarray of bool, shape (n_dof,), optional
        The coordinates integrated (default all; prescribed motion integrates only
        the free ones).
    """
    if not isinstance(arm, FlexibleArm):
        return math.inf
    n = arm.n_dof
    q0 = np.zeros(n) if q is None else np.asarray(q, dtype=np.float64)
    M, K, D = _linear_matrices(arm, q0)
    keep = np.ones(n, dtype=bool) if free is None else np.asarray(free, dtype=bool)
    M, K, D = (A[np.ix_(keep, keep)] for A in (M, K, D))
    m = M.shape[0]
    if m == 0:
        return math.inf
    Minv = np.linalg.inv(M)
    A = np.block([[np.zeros((m, m)), np.eye(m)], [-Minv @ K, -Minv @ D]])
    lam = np.asarray(np.linalg.eigvals(A), dtype=np.complex128)
    lam = lam[np.abs(lam) > 0]
    if lam.size == 0:
        return math.inf
    hi = 4.0 / float(np.max(np.abs(lam)))  # the stable region ends before |z| = 2.83
    lo = 0.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if np.all(rk4_growth(mid * lam) <= 1.0 + 1e-12):
            lo = mid
        else:
            hi = mid
    return lo


def check_substeps(
    arm: Plant,
    dt: float,
    substeps: int | str,
    owner: str,
    q: ArrayLike | None = None,
    free: NDArray[np.bool_] | None = None,
) -> int:
    """The substeps per interval ``dt`` (s): ``"auto"`` takes 1 where one step is
    stable, else the fewest whose step is within :data:`MARGIN` of the stable bound;
    an integer is checked against the bound itself.

    Raises
    ------
    UnstableStepError
        (an InvalidValueError) For an integer whose step is beyond the bound, naming
        the substeps that work.
    """
    h_max = stable_step(arm, q, free)
    if substeps == "auto":
        if dt <= h_max:
            return 1
        return math.ceil(dt / (MARGIN * h_max))
    assert isinstance(substeps, int)
    if dt / substeps > h_max:
        need = math.ceil(dt / (MARGIN * h_max))
        raise UnstableStepError(
            f"The 'substeps' parameter of {owner} must be at least {need} for this arm: a "
            f"step of {dt / substeps:.3g} s is beyond the RK4 stability bound of its "
            f"dynamics linearised at the start ({h_max:.3g} s; a stiff joint, a high mode or "
            f"steep friction), and the run would diverge at once. Got {substeps} instead "
            "(substeps='auto' chooses)."
        )
    return substeps
