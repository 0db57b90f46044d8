"""Linear-quadratic designs: the regulator (LQR) and the Kalman filter (LQE).

Continuous time (``StateSpace.dt`` None) or sampled, with the conventions of
python-control (``lqr``, ``dlqr``, ``lqe``, ``dlqe``), which the tests hold these
to:

* :func:`lqr` minimises ``sum x' Q x + u' R u`` (or the integral): ``u = -K x``.
* :func:`kalman` for ``x' = A x + B u + G w``, ``y = C x + v`` with
  ``E[w w'] = Qn``, ``E[v v'] = Rn``: the gain ``L`` of the estimator
  ``xe' = A xe + B u + L (y - C xe)`` (continuous), or of the one-step
  predictor ``xe[k+1] = A xe[k] + B u[k] + L (y[k] - C xe[k])`` (sampled), and
  for a sampled model also the filter gain ``M`` of the measurement update
  ``x[k|k] = x[k|k-1] + M (y[k] - C x[k|k-1])`` (``L = A M``).

Weights must be symmetric, ``Q`` and ``Qn`` positive semidefinite, ``R`` and
``Rn`` positive definite; ``(A, B)`` stabilisable and ``(A, C)`` detectable (an
unobservable unstable or marginal mode, e.g. a sensor that cannot see a
rigid-body motion, is refused with the mode named).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._types import F64
from .._validation import check_array
from ..errors import InvalidValueError
from .statespace import StateSpace

__all__ = ["Estimator", "Regulator", "check_detectable", "kalman", "lqr"]


class Regulator(NamedTuple):
    """What :func:`lqr` returns: the gain ``K`` (m, n), the Riccati solution ``S``
    (n, n) and the closed-loop poles (eigenvalues of ``A - B K``)."""

    K: F64
    S: F64
    poles: NDArray[np.complex128]


class Estimator(NamedTuple):
    """What :func:`kalman` returns: the predictor gain ``L`` (n, p), the filter gain
    ``M`` (n, p; sampled models; ``L`` again for continuous ones), the Riccati
    solution ``P`` (n, n) and the estimator poles (eigenvalues of ``A - L C``)."""

    L: F64
    M: F64
    P: F64
    poles: NDArray[np.complex128]


def _weight(value: ArrayLike, name: str, owner: str, n: int, definite: bool) -> F64:
    w = check_array(value, name, owner)
    if w.ndim == 0:
        w = float(w) * np.eye(n)
    elif w.ndim == 1 and w.shape == (n,):
        w = np.diag(w)
    if w.shape != (n, n):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be a scalar, of shape ({n},) or ({n}, {n}). "
            f"Got shape {w.shape} instead."
        )
    if not np.allclose(w, w.T, rtol=1e-10, atol=1e-12 * max(1.0, float(np.abs(w).max()))):
        raise InvalidValueError(f"The '{name}' parameter of {owner} must be symmetric.")
    w = np.asarray(0.5 * (w + w.T), dtype=np.float64)
    low = float(np.linalg.eigvalsh(w).min())
    scale = max(1.0, float(np.abs(w).max()))
    if definite and not low > 1e-14 * scale:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be positive definite. Got smallest "
            f"eigenvalue {low:.3g} instead."
        )
    if not definite and low < -1e-12 * scale:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be positive semidefinite. Got smallest "
            f"eigenvalue {low:.3g} instead."
        )
    return w


def check_detectable(sys: StateSpace, owner: str, what: str = "sensor") -> None:
    """Refuse ``(A, C)`` with an unstable or marginal mode that ``C`` cannot see
    (Popov–Belevitch–Hautus test), naming ``what`` as the parameter at fault."""
    n = sys.n_states
    lam, vec = np.linalg.eig(sys.A)
    for k, z in enumerate(lam):
        marginal = z.real >= -1e-9 * max(1.0, abs(z)) if sys.dt is None else abs(z) >= 1 - 1e-9
        if not marginal:
            continue
        pbh = np.vstack([z * np.eye(n) - sys.A, sys.C])
        sv = np.linalg.svd(pbh, compute_uv=False)
        if sv[-1] < 1e-9 * sv[0]:
            mode = vec[:, k]
            strongest = sys.state_names[int(np.argmax(np.abs(mode)))]
            raise InvalidValueError(
                f"The '{what}' parameter of {owner} must see every unstable or marginal mode: "
                f"the mode at {z:.4g} (mostly {strongest}) is unobservable from "
                f"{', '.join(sys.output_names)}."
            )


def _riccati(sys: StateSpace, a: F64, b: F64, q: F64, r: F64, failure: str) -> F64:
    """The stabilising solution of the algebraic Riccati equation of ``sys``'s kind
    (continuous or discrete) for ``(a, b, q, r)``; ``failure`` begins the message
    when there is none."""
    import scipy.linalg

    solve = scipy.linalg.solve_continuous_are if sys.dt is None else scipy.linalg.solve_discrete_are
    try:
        x: F64 = solve(a, b, q, r)
    except (np.linalg.LinAlgError, ValueError) as exc:
        # SciPy's balancing can itself leave the pencil too ill-conditioned to reorder
        # (a sampled model with poles near z = 1 on both sides of it, as an arm holding
        # its weight has): the unbalanced pencil, before giving up
        try:
            x = solve(a, b, q, r, balanced=False)
        except (np.linalg.LinAlgError, ValueError):
            raise InvalidValueError(f"{failure}: {exc}") from exc
    return x


def lqr(sys: StateSpace, Q: ArrayLike, R: ArrayLike) -> Regulator:
    """The linear-quadratic regulator of ``sys`` (continuous or sampled).

    Parameters
    ----------
    sys : StateSpace
    Q : array_like, shape (n, n), (n,) or scalar
        State weight (positive semidefinite).
    R : array_like, shape (m, m), (m,) or scalar
        Input weight (positive definite).
    """
    owner = "lqr"
    q = _weight(Q, "Q", owner, sys.n_states, definite=False)
    r = _weight(R, "R", owner, sys.n_inputs, definite=True)
    a, b = sys.A, sys.B
    failure = f"The 'Q' parameter of {owner} gives no stabilising solution with this model"
    s = _riccati(sys, a, b, q, r, f"{failure} (is (A, B) stabilisable and (A, Q) detectable?)")
    if sys.dt is None:
        k: F64 = np.asarray(np.linalg.solve(r, b.T @ s), dtype=np.float64)
    else:
        k = np.asarray(np.linalg.solve(r + b.T @ s @ b, b.T @ s @ a), dtype=np.float64)
    poles = np.asarray(np.linalg.eigvals(a - b @ k), dtype=np.complex128)
    return Regulator(K=k, S=s, poles=poles)


def kalman(sys: StateSpace, G: ArrayLike, Qn: ArrayLike, Rn: ArrayLike) -> Estimator:
    """The steady-state Kalman filter of ``sys`` (module docstring).

    Parameters
    ----------
    sys : StateSpace
    G : array_like, shape (n, w)
        Where the process noise enters.
    Qn : array_like, shape (w, w), (w,) or scalar
        Process-noise covariance (positive semidefinite).
    Rn : array_like, shape (p, p), (p,) or scalar
        Measurement-noise covariance (positive definite).
    """
    owner = "kalman"
    g = check_array(G, "G", owner, shape=(sys.n_states, -1))
    qn = _weight(Qn, "Qn", owner, g.shape[1], definite=False)
    rn = _weight(Rn, "Rn", owner, sys.n_outputs, definite=True)
    check_detectable(sys, owner)
    a, c = sys.A, sys.C
    gqg = g @ qn @ g.T
    gqg = 0.5 * (gqg + gqg.T)
    failure = f"The 'Qn' parameter of {owner} gives no stabilising filter with this model"
    p = _riccati(sys, a.T, c.T, gqg, rn, f"{failure} (is (A, G) stabilisable?)")
    if sys.dt is None:
        gain: F64 = np.asarray(np.linalg.solve(rn, c @ p).T, dtype=np.float64)
        m = gain
    else:
        m = np.asarray(np.linalg.solve(c @ p @ c.T + rn, c @ p).T, dtype=np.float64)
        gain = a @ m
    poles = np.asarray(np.linalg.eigvals(a - gain @ c), dtype=np.complex128)
    return Estimator(L=gain, M=m, P=p, poles=poles)
