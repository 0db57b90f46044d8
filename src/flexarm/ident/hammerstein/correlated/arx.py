r"""ARX-Hammerstein models of a fixed structure: over-parameterised least squares,
rank-one separation, instrumental-variable refinement (the correlated-input path).

Model (the paper's Hammerstein system, Fig. 5, any input):

.. math:: y_n - \bar y = \sum_{i=1}^{l} a_i (y_{n-i} - \bar y)
          + \sum_{j=0}^{l} b_j \varphi(u_{n-j}) + e_n ,

``phi`` piecewise linear on ``K`` knots at the input's quantiles
(:mod:`flexarm.ident.hammerstein.correlated.hatbasis`), normalised to mean zero over the inputs.

Estimation, for a given order ``l`` and knot count ``K``
----------------------------------------------------------
1. **Over-parameterised least squares** (Chang & Luus 1971; Bai 1998): with
   ``phi = sum_k c_k g_k``, the products ``theta_jk = b_j c_k`` enter linearly,
   so ``y`` is regressed on its lags and on the hats of the lagged inputs
   (centred: the intercept is profiled out). The normal equations are summed
   by a compiled loop (``flexarm.ident.hammerstein.correlated._loops``) that touches the
   ``l + 2 (l + 1)`` non-zero entries of each row only.
2. **Rank-one separation** (Bai's two-stage algorithm): the ``(l + 1) x (K - 1)``
   array ``theta_jk`` is ``b c^T``; its leading singular pair gives ``b`` and
   the knot values ``c`` (the reference knot's value is 0). The ratio of the
   second singular value to the first measures how far the data are from a
   Hammerstein structure.
3. **Instrumental variables** (Stoica & Söderström 1982; Söderström & Stoica
   1983, "IV4" without prefilter). The paper's noise enters before the linear
   part, ``W_n = phi(X_n) + xi_n``, so the equation error ``e_n = sum_j b_j
   xi_{n-j}`` is coloured and correlated with the lagged outputs: least
   squares is biased. The instruments replace the lagged outputs by the
   noise-free simulated output of the current model; the system is solved
   again and separated again. A step is **kept only if it lowers the
   free-run (output-error) mean square error** on the estimation samples (with
   the output offset that fits the free run best) —
   the output-error criterion, which the true system minimises whatever the
   noise colour. On data that do not follow the paper's noise model
   (the DaISy arm) the instruments can lose, and least squares is kept.

The linear algebra is small (at most a few hundred unknowns), so it runs on one
BLAS thread (:func:`one_blas_thread`, through ``threadpoolctl`` when it is
installed — scikit-learn brings it): on a busy machine a multithreaded BLAS
spends more time waiting for its threads than solving.

References
----------
* H.-F. Chang, R. Luus, "A noniterative method for identification using
  Hammerstein model", IEEE Trans. Automat. Control 16 (1971) 464–468.
* E.-W. Bai, "An optimal two-stage identification algorithm for
  Hammerstein–Wiener nonlinear systems", Automatica 34 (1998) 333–338.
* P. Stoica, T. Söderström, "Instrumental-variable methods for identification
  of Hammerstein systems", Int. J. Control 35 (1982) 459–476.
* T. Söderström, P. Stoica, *Instrumental Variable Methods for System
  Identification*, Springer LNCIS 57 (1983).
"""

from __future__ import annotations

import importlib
from contextlib import AbstractContextManager, nullcontext
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...._types import F64, I64
from ..systems import spectral_radius
from ._loops import hammerstein_gram, instrument_cross
from .hatbasis import evaluate, locate, quantile_knots

__all__ = ["Design", "Located", "StructureFit", "fit_structure", "n_params", "one_blas_thread"]


#: Instrumental-variable steps tried after least squares (each kept only if it helps).
MAX_IV_STEPS = 4
#: Relative decrease of the output error below which the steps stop (converged).
IV_TOLERANCE = 1e-6


def one_blas_thread() -> AbstractContextManager[Any]:
    """A context in which BLAS runs on one thread (``threadpoolctl``), or a no-op without it."""
    try:  # optional (no type information): imported by name
        threadpoolctl = importlib.import_module("threadpoolctl")
    except ImportError:  # pragma: no cover - optional
        return nullcontext()
    limits: AbstractContextManager[Any] = threadpoolctl.threadpool_limits(limits=1, user_api="blas")
    return limits


def n_params(order: int, n_knots: int) -> int:
    """Parameters of the over-parameterised regression: ``l + (l + 1) (K - 1)``."""
    return order + (order + 1) * (n_knots - 1)


@dataclass(frozen=True)
class StructureFit:
    """An ARX-Hammerstein model of order ``l`` with ``K`` knots (module docstring).

    Attributes
    ----------
    order : int
        ``l``: AR coefficients ``a_1 .. a_l``, MA coefficients ``b_0 .. b_l``.
    knots : ndarray, shape (K,)
        Knots (units of ``u``).
    phi : ndarray, shape (K,)
        Values of the nonlinearity at the knots, mean zero over the inputs of
        the regression rows (scale and sign set by the separation).
    a, b : ndarray, shapes (l,) and (l + 1,)
        The linear part in the paper's ARMA convention.
    offset : float
        Output offset (units of ``y``): the mean, over the estimation samples,
        of the output minus the model's free run from rest — the constant that
        best fits the free run (no division by ``A(1)``, which is near zero
        for a lightly damped system).
    singular_values : ndarray, shape (min(l + 1, K - 1),)
        Of the array ``theta_jk = b_j c_k`` (rank one for a Hammerstein system).
    estimator : str
        ``"least squares"`` or ``"instrumental variables"``.
    iv_steps : int
        Instrumental-variable steps kept.
    output_mse : float
        Free-run mean square error on the estimation samples, offset included
        (units of ``y`` squared).
    history : tuple of float
        ``output_mse`` after least squares and after each step tried.
    """

    order: int
    knots: F64
    phi: F64
    a: F64
    b: F64
    offset: float
    singular_values: F64
    estimator: str
    iv_steps: int
    output_mse: float
    history: tuple[float, ...] = field(default=())

    @property
    def n_knots(self) -> int:
        """``K``, the knots in use (fewer than asked when the input takes few values)."""
        return int(self.knots.shape[0])

    @property
    def n_params(self) -> int:
        """Parameters of the over-parameterised regression."""
        return n_params(self.order, self.n_knots)

    def nonlinearity(self, u: F64) -> F64:
        """``phi(u)``, shape of ``u`` (1-D), linear beyond the end knots."""
        return evaluate(*locate(u, self.knots), self.phi)

    def simulate(self, u: F64) -> F64:
        """Free-run output from rest for the inputs ``u``, shape (n,) (units of ``y``)."""
        return self.simulate_located(*locate(u, self.knots))

    def simulate_located(self, segment: I64, position: F64) -> F64:
        """:meth:`simulate` for inputs already located on ``knots`` (:func:`locate`)."""
        from scipy.signal import lfilter

        w = evaluate(segment, position, self.phi)
        out: F64 = np.asarray(lfilter(self.b, np.r_[1.0, -self.a], w), dtype=np.float64)
        return out + self.offset


@dataclass(frozen=True)
class Design:
    """Which samples of a record estimate, and how its free run is simulated.

    Attributes
    ----------
    segments : ndarray of int64, shape (m, 2)
        Estimation segments ``[a, b)``: the regression rows (whose lags stay in
        a segment), the knots and the means come from them.
    runs : ndarray of int64, shape (r, 2)
        Free runs ``[s0, e)``, each simulated from rest (a run's first samples
        are its burn-in); they cover the estimation samples.
    mask : ndarray of bool, shape (n,)
        The estimation samples scored by the output error.
    """

    segments: I64
    runs: I64
    mask: NDArray[np.bool_]

    @classmethod
    def whole(cls, n: int) -> Design:
        """Every sample of an ``n``-sample record, one free run."""
        full = np.array([[0, n]], dtype=np.int64)
        return cls(full, full, np.ones(n, dtype=bool))

    def free_run(self, b: F64, a: F64, seg: I64, pos: F64, phi: F64) -> F64:
        """``B/A phi(u)`` from rest over each run, shape (n,) (zero outside the runs)."""
        from scipy.signal import lfilter

        out = np.zeros(self.mask.shape[0])
        den = np.r_[1.0, -a]
        for s0, e in self.runs:
            w = evaluate(seg[s0:e], pos[s0:e], phi)
            out[s0:e] = lfilter(b, den, w)
        return out


@dataclass
class _Problem:
    """The regression of one structure on one record (sums shared by LS and IV)."""

    yc: F64
    y_mean: float
    seg: I64
    pos: F64
    order: int
    knots: F64
    ref: int
    design: Design
    stride: int
    gram: F64
    rhs: F64
    sums: F64
    total: float
    count: int

    @property
    def k(self) -> int:
        return int(self.knots.shape[0])

    def separate(self, theta: F64) -> tuple[F64, F64, F64, F64] | None:
        """``(a, b, phi, singular values)`` from the regression coefficients, or None."""
        order, k = self.order, self.k
        if not np.all(np.isfinite(theta)):
            return None
        arr = theta[order:].reshape(order + 1, k - 1)
        left, s, right = np.linalg.svd(arr, full_matrices=False)
        if not s[0] > 0.0:
            return None
        b = left[:, 0] * s[0]
        c = np.insert(right[0], self.ref, 0.0)
        # mean of phi over the rows' inputs, from the column sums of lag 0
        mean = float(right[0] @ self.sums[order : order + k - 1]) / self.count
        phi = c - mean
        a = np.ascontiguousarray(theta[:order])
        return a, np.ascontiguousarray(b), phi, s

    def output(self, a: F64, b: F64, phi: F64) -> F64:
        """Free-run output from rest, without offset, over the design's runs."""
        return self.design.free_run(b, a, self.seg, self.pos, phi)

    def output_fit(self, a: F64, b: F64, phi: F64) -> tuple[float, float]:
        """``(offset, mse)``: the best output offset of the free run and its mean
        square error over the estimation samples (offset relative to the centring)."""
        mask = self.design.mask
        err = (self.yc - self.output(a, b, phi))[mask]
        offset = float(np.mean(err))
        return offset, float(np.mean((err - offset) ** 2))

    def instrumental(self, x: F64) -> F64 | None:
        """The IV solution with the simulated deviation output ``x`` as instrument."""
        p = self.order
        d = self.gram.shape[0]
        block = np.zeros((p, d))
        zs = np.zeros(p)
        zc = np.zeros(p)
        instrument_cross(
            x, self.yc, self.seg, self.pos, p, p, self.k, self.ref,
            self.design.segments, self.stride, block, zs, zc,
        )  # fmt: skip
        mat = np.vstack([block - np.outer(zs, self.sums) / self.count, self.gram[p:]])
        rhs = np.r_[zc - zs * self.total / self.count, self.rhs[p:]]
        return _solve(mat, rhs, symmetric=False)


def _solve(mat: F64, rhs: F64, symmetric: bool) -> F64 | None:
    """``mat x = rhs`` with the columns scaled to unit diagonal; None if singular.

    Symmetric (least squares): Cholesky, else an SVD-based least-squares
    solution; otherwise (instrumental variables) LU.
    """
    from scipy.linalg import LinAlgError, cho_factor, cho_solve, lu_factor, lu_solve

    diag = np.sqrt(np.abs(np.diag(mat)))
    diag[diag == 0.0] = 1.0
    scaled = mat / diag[None, :] / diag[:, None]
    try:
        if symmetric:
            try:
                x = cho_solve(cho_factor(scaled, check_finite=False), rhs / diag)
            except LinAlgError:
                x = np.linalg.lstsq(scaled, rhs / diag, rcond=None)[0]
        else:
            x = lu_solve(lu_factor(scaled, check_finite=False), rhs / diag)
    except (LinAlgError, ValueError):
        return None
    out: F64 = x / diag
    return out if np.all(np.isfinite(out)) else None


@dataclass(frozen=True)
class Located:
    """Knots at the quantiles of the estimation inputs, and every input located on them."""

    knots: F64
    segment: I64
    position: F64

    @classmethod
    def of(cls, u: F64, u_sorted: F64, n_knots: int) -> Located:
        """``n_knots`` knots at the quantiles of ``u_sorted``; ``u`` (shape (n,)) located."""
        knots = quantile_knots(u_sorted, n_knots)
        return cls(knots, *locate(u, knots))


def _problem(y: F64, order: int, where: Located, design: Design, stride: int) -> _Problem:
    k = where.knots.shape[0]
    seg, pos = where.segment, where.position
    ref = k // 2
    y_mean = float(np.mean(y[design.mask]))
    yc = y - y_mean
    d = n_params(order, k)
    gram = np.zeros((d, d))
    sums = np.zeros(d)
    cross = np.zeros(d)
    count, total = hammerstein_gram(
        yc, seg, pos, order, order, k, ref, design.segments, stride, gram, sums, cross
    )
    gram += np.triu(gram, 1).T  # the loop fills the upper triangle
    gram -= np.outer(sums, sums) / count
    rhs = cross - sums * total / count
    knots = where.knots
    return _Problem(
        yc, y_mean, seg, pos, order, knots, ref, design, stride, gram, rhs, sums, total, count
    )


def fit_structure(
    u: F64,
    y: F64,
    order: int,
    n_knots: int,
    *,
    design: Design | None = None,
    stride: int = 1,
    instruments: int = MAX_IV_STEPS,
    located: Located | None = None,
) -> StructureFit | None:
    """Fit the ARX-Hammerstein model of order ``order`` with ``n_knots`` knots.

    Parameters
    ----------
    u, y : ndarray, shape (n,)
        Input and output (any units), finite.
    order : int
        ``l >= 1``.
    n_knots : int
        ``K >= 2`` knots at the quantiles of the estimation inputs (2: a linear model).
    design : Design, optional
        Which samples estimate and how the free run is simulated (default the
        whole record, :meth:`Design.whole`).
    stride : int
        Use every ``stride``-th regression row in the sums (the output-error
        check uses every sample).
    instruments : int
        Instrumental-variable steps tried after least squares (0: none).
    located : Located, optional
        The knots and located inputs, when already known (``n_knots`` is then ignored).

    Returns
    -------
    StructureFit or None
        None when no stable model comes out (the structure is then unusable).
    """
    design = Design.whole(u.shape[0]) if design is None else design
    if located is None:
        located = Located.of(u, np.sort(u[design.mask]), n_knots)
    prob = _problem(y, order, located, design, stride)
    theta = _solve(prob.gram, prob.rhs, symmetric=True)
    parts = None if theta is None else prob.separate(theta)
    best: tuple[F64, F64, F64, F64] | None = None
    best_mse, best_offset = np.inf, 0.0
    if parts is not None and spectral_radius(parts[0]) < 1.0:
        best = parts
        best_offset, best_mse = prob.output_fit(*parts[:3])
    history = [best_mse]
    steps = 0
    current = parts
    for _ in range(instruments):
        if current is None or not spectral_radius(current[0]) < 1.0:
            break
        theta = prob.instrumental(prob.output(*current[:3]))
        current = None if theta is None else prob.separate(theta)
        if current is None or not spectral_radius(current[0]) < 1.0:
            history.append(np.inf)
            break
        offset, mse = prob.output_fit(*current[:3])
        history.append(mse)
        if not mse < best_mse:
            break
        converged = mse > best_mse * (1.0 - IV_TOLERANCE)
        best, best_mse, best_offset, steps = current, mse, offset, steps + 1
        if converged:
            break
    if best is None:
        return None
    a, b, phi, s = best
    return StructureFit(
        order=order,
        knots=prob.knots,
        phi=phi,
        a=a,
        b=b,
        offset=prob.y_mean + best_offset,
        singular_values=s,
        estimator="instrumental variables" if steps else "least squares",
        iv_steps=steps,
        output_mse=best_mse,
        history=tuple(history),
    )
