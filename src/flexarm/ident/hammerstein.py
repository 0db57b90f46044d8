r"""Nonparametric identification of Hammerstein systems (paper §5, Fig. 5).

Model: ``W_n = phi(X_n) + xi_n``, ``Y_n = sum_k lambda_k W_{n-k}`` (a stable ARMA
subsystem, :mod:`flexarm.ident.systems`), the input ``X_n`` i.i.d.

Method
------
For an i.i.d. input, every lag ``k >= 0`` gives the regression

.. math:: m_k(x) = E[Y_{n+k} \mid X_n = x] = \lambda_k \varphi(x) + c_k ,

so the centred lag regressions ``m_k - E m_k(X)`` form a rank-one array
``lambda_k (phi(x) - E phi(X))``. :class:`HammersteinIdentifier` estimates
each ``m_k``, ``k = 0 .. n_lags - 1``, by the paper's semi-recursive kernel
estimate (eq. 14, :class:`~flexarm.ident.SemiRecursiveKernelRegression` in grid
mode) and then:

1. **Linear part, correlation approach.** ``lambda_k`` up to scale is the
   covariance of ``Y_{n+k}`` with an *instrument* ``psi(X_n)``,
   ``cov(Y_{n+k}, psi(X_n)) = lambda_k cov(phi(X), psi(X))``, estimated as
   ``sum_g p_g psi(x_g) (m_k(x_g) - mean_k)`` over the grid with the kernel
   density weights ``p_g`` (the regressions' denominators). Instruments:

   * ``"input"``: ``psi(x) = x`` — the classical choice; it fails when
     ``cov(phi(X), X) = 0``, e.g. an even ``phi`` with a symmetric input;
   * ``"regression"``: ``psi = m_0``, the estimated regression function itself
     (the paper's suggestion): works for even ``phi`` as long as ``lambda_0 =
     b0 != 0``;
   * ``"auto"`` (default): ``psi`` = the estimated ``phi`` itself, i.e. the
     fixed point of "instrument -> impulse response -> combined shape ->
     instrument", computed in closed form as the leading singular pair of the
     density-weighted array ``sqrt(p_g) (m_k(x_g) - mean_k)``. It is the best
     instrument (``cov(phi, psi)`` largest), works for even ``phi`` and for a
     delayed linear part (``b0 = 0``).

2. **Nonlinearity.** The shape ``psi(x) = sum_k lambda_k (m_k(x) - mean_k) /
   sum_k lambda_k**2`` (the least-squares combination of the lag
   regressions; with ``n_lags = 1`` it is the paper's ``m_n`` itself) is
   ``phi`` up to an affine map. With ``known_points = ((x1, phi1), (x2,
   phi2))`` the paper's two-point normalisation fixes it:
   ``d1 = (psi(x1) - psi(x2)) / (phi1 - phi2)``, ``alpha = psi(x1) - d1 phi1``,
   ``phi_n(x) = (psi(x) - alpha) / d1``, and the impulse response is scaled
   accordingly (``lambda_k d1``). **Without known points** ``phi`` and the
   impulse response are identified only up to ``phi -> s phi + t``,
   ``lambda -> lambda / s``: the estimate is then normalised so that the
   impulse response's entry of largest magnitude is ``+1`` and
   ``phi`` has mean zero under the input distribution; the output offset this
   leaves is carried by ``offset_`` so that :meth:`~HammersteinIdentifier.predict`
   still reproduces the output.

3. **ARMA coefficients** from the impulse response by least squares on the
   impulse response (:func:`arma_from_impulse_response`): for each order
   ``l = 0 .. max_order`` (the paper's ``ARMA(l, l)``), Prony's linear
   least-squares start, refined by nonlinear least squares on
   ``sum_k (lambda_k - h_k(a, b))**2``, unstable fits reflected inside the unit
   circle; the order minimising an information criterion (BIC by default:
   ``L ln(RSS / L) + (2 l + 1) ln L`` over the ``L = n_lags`` coefficients) is
   kept.

Defaults and scale
------------------
``bandwidth="auto"`` sets ``h_1 = 0.5 s`` with ``s`` the standard deviation
of the first ``warmup`` inputs (``h_i = h_1 i**-decay`` after that), and the
grid spans their range widened by 10 % on each side: nothing depends on the
units of ``u`` or ``y``. Outside the grid the estimate is held at its end
values.

Streaming
---------
The state is the ``n_lags`` grid-mode regressions (running sums), the last
``n_lags - 1`` inputs and sequential running sums of ``y``; the first
``warmup`` samples are buffered until the scale is known. Samples enter every
sum in arrival order, so :meth:`~HammersteinIdentifier.partial_fit` on chunks
equals :meth:`~HammersteinIdentifier.fit` on the whole record bit for bit.
The impulse response, nonlinearity and ARMA model are derived from the state
when first asked for after an update.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Self

import numba as nb
import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import check_array, check_int, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ._params import HyperParameters
from .kernels import KERNELS
from .regression import NotFittedError, SemiRecursiveKernelRegression
from .systems import ARMA, spectral_radius

__all__ = [
    "ARMAFit",
    "HammersteinIdentifier",
    "arma_from_impulse_response",
    "fit_percent",
    "two_point_normalisation",
]

F64 = NDArray[np.float64]
_OWNER = "HammersteinIdentifier"
_INSTRUMENTS = ("auto", "regression", "input")
_CRITERIA = ("bic", "aic")


@nb.njit(cache=True)
def _running_sums(y: F64, acc: F64) -> None:  # pragma: no cover - compiled
    """``acc[0] += sum y``, ``acc[1] += sum y**2``, one sample at a time in order."""
    for i in range(y.shape[0]):
        acc[0] += y[i]
        acc[1] += y[i] * y[i]


# --------------------------------------------------------------------------- helpers


def fit_percent(y: ArrayLike, y_hat: ArrayLike) -> float:
    """Fit in percent, ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` (100 is perfect).

    Parameters
    ----------
    y : array_like, shape (n,)
        Measured output.
    y_hat : array_like, shape (n,)
        Model output, same units.

    Examples
    --------
    >>> fit_percent([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    100.0
    """
    ya = check_array(y, "y", "fit_percent", shape=(-1,))
    yh = check_array(y_hat, "y_hat", "fit_percent", shape=ya.shape)
    spread = float(np.linalg.norm(ya - ya.mean()))
    if spread == 0.0:
        raise InvalidValueError(
            "The 'y' parameter of fit_percent must vary. Got a constant instead."
        )
    return 100.0 * (1.0 - float(np.linalg.norm(ya - yh)) / spread)


def two_point_normalisation(m1: float, m2: float, phi1: float, phi2: float) -> tuple[float, float]:
    """The paper's two-point normalisation: ``(d1, alpha)`` with ``phi = (m - alpha) / d1``.

    ``d1 = (m1 - m2) / (phi1 - phi2)`` and ``alpha = m1 - d1 phi1``, where
    ``m1, m2`` are the (unnormalised) estimates at two points where ``phi`` is
    known to be ``phi1 != phi2``.

    Examples
    --------
    >>> two_point_normalisation(3.0, 1.0, 1.0, 0.0)
    (2.0, 1.0)
    """
    owner = "two_point_normalisation"
    m1, m2 = check_real(m1, "m1", owner), check_real(m2, "m2", owner)
    phi1, phi2 = check_real(phi1, "phi1", owner), check_real(phi2, "phi2", owner)
    if phi1 == phi2:
        raise InvalidValueError(
            f"The 'phi2' parameter of {owner} must differ from phi1. Got {phi2}."
        )
    d1 = (m1 - m2) / (phi1 - phi2)
    if d1 == 0.0:
        raise InvalidValueError(
            f"The 'm2' parameter of {owner} must differ from m1 (the estimate must separate "
            f"the two points). Got {m2} instead."
        )
    return d1, m1 - d1 * phi1


@dataclass(frozen=True)
class ARMAFit:
    """An ARMA model fitted to an impulse response, with the order selection record.

    Attributes
    ----------
    model : ARMA
        The selected model.
    order : int
        Its order ``l`` (``ARMA(l, l)``).
    criterion : dict of int to float
        Information criterion of every order tried.
    rss : dict of int to float
        Residual sum of squares of the impulse response for every order tried.
    """

    model: ARMA
    order: int
    criterion: dict[int, float] = field(default_factory=dict)
    rss: dict[int, float] = field(default_factory=dict)


def _stabilise(a: F64) -> F64:
    """Reflect AR roots on or outside the unit circle to ``0.999 / conj(r)``."""
    if a.shape[0] == 0 or spectral_radius(a) < 1.0:
        return a
    roots = np.roots(np.r_[1.0, -a])
    big = np.abs(roots) >= 1.0
    roots[big] = 0.999 / np.conj(roots[big])
    out: F64 = -np.real(np.poly(roots))[1:]
    return out


def _impulse(a: F64, b: F64, n: int) -> F64:
    from scipy.signal import lfilter

    delta = np.zeros(n)
    delta[0] = 1.0
    out: F64 = np.asarray(lfilter(b, np.r_[1.0, -a], delta), dtype=np.float64)
    return out


def _fit_order(h: F64, order: int) -> tuple[F64, F64]:
    """ARMA(order, order) fitted to ``h`` (Prony start, nonlinear least-squares refinement)."""
    from scipy.optimize import least_squares

    L = h.shape[0]
    p = order
    if p == 0:
        return np.zeros(0), h[:1].copy()
    rows = np.array([h[k - p : k][::-1] for k in range(p + 1, L)])
    a = np.linalg.lstsq(rows, h[p + 1 : L], rcond=None)[0] if rows.size else np.zeros(p)
    a = _stabilise(np.asarray(a, dtype=np.float64))
    b = np.array([h[j] - sum(a[i - 1] * h[j - i] for i in range(1, j + 1)) for j in range(p + 1)])

    def resid(theta: F64) -> F64:
        return _impulse(theta[:p], theta[p:], L) - h

    try:
        sol = least_squares(resid, np.r_[a, b], method="lm", max_nfev=200 * (2 * p + 1))
        a2, b2 = sol.x[:p], sol.x[p:]
        if spectral_radius(a2) < 1.0 and np.sum(resid(sol.x) ** 2) <= np.sum(
            resid(np.r_[a, b]) ** 2
        ):
            a, b = a2, b2
    except (ValueError, np.linalg.LinAlgError):  # pragma: no cover - keep the Prony start
        pass
    return np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)


def arma_from_impulse_response(
    h: ArrayLike, order: int | str = "bic", max_order: int = 4
) -> ARMAFit:
    """Fit the paper's ARMA(l, l) model to an impulse response ``h_0 .. h_{L-1}``.

    For each ``l`` the AR part comes from Prony's equations
    ``h_k = a1 h_{k-1} + ... + al h_{k-l}`` (``k > l``) by linear least squares,
    the MA part from ``b_j = h_j - sum_i a_i h_{j-i}`` (``j <= l``); both are
    then refined by nonlinear least squares on the impulse-response error
    (Levenberg–Marquardt), keeping the refinement only if it is stable and
    better. Unstable AR roots are reflected inside the unit circle.

    Parameters
    ----------
    h : array_like, shape (L,)
        Impulse response (``L >= 2 max_order + 2``).
    order : int or {"bic", "aic"}
        A fixed order ``l``, or the criterion that selects it:
        BIC ``L ln(RSS/L) + (2l+1) ln L`` or AIC ``L ln(RSS/L) + 2 (2l+1)``,
        with ``RSS`` floored at ``1e-12 sum h**2`` (ties go to the lower order).
    max_order : int
        Largest ``l`` tried by a criterion.

    Returns
    -------
    ARMAFit

    Examples
    --------
    >>> h = ARMA((0.5,), (1.0, 0.3)).impulse_response(30)
    >>> fit = arma_from_impulse_response(h)
    >>> fit.order, [round(v, 6) for v in fit.model.a + fit.model.b]
    (1, [0.5, 1.0, 0.3])
    """
    owner = "arma_from_impulse_response"
    ha = check_array(h, "h", owner, shape=(-1,))
    max_order = check_int(max_order, "max_order", owner, minimum=0)
    if isinstance(order, str):
        check_option(order, "order", owner, _CRITERIA)
        orders = list(range(max_order + 1))
    else:
        orders = [check_int(order, "order", owner, minimum=0)]
    L = ha.shape[0]
    need = 2 * max(orders) + 2
    if need > L:
        raise InvalidValueError(
            f"The 'h' parameter of {owner} must hold >= {need} values for order "
            f"{max(orders)}. Got {L} instead."
        )
    if not np.any(ha != 0.0):
        raise InvalidValueError(
            f"The 'h' parameter of {owner} must not be all zero. Got zeros instead."
        )
    floor = 1e-12 * float(np.sum(ha**2))
    crit: dict[int, float] = {}
    rss: dict[int, float] = {}
    models: dict[int, ARMA] = {}
    for order_l in orders:
        a, b = _fit_order(ha, order_l)
        if not np.any(b != 0.0):
            continue
        r = float(np.sum((_impulse(a, b, L) - ha) ** 2))
        k = 2 * order_l + 1
        penalty = k * np.log(L) if order != "aic" else 2.0 * k
        crit[order_l] = float(L * np.log(max(r, floor) / L) + penalty)
        rss[order_l] = r
        models[order_l] = ARMA(tuple(a.tolist()), tuple(b.tolist()))
    best = min(crit, key=lambda o: (crit[o], o))
    return ARMAFit(models[best], best, crit, rss)


# --------------------------------------------------------------------------- estimator


@dataclass(frozen=True)
class _Solution:
    lags: F64  # lambda-tilde, unnormalised
    shape: F64  # psi on the valid grid points
    grid: F64  # valid grid points
    weights: F64  # density weights p_g on them (sum 1)
    impulse: F64
    nonlinearity: F64
    arma: ARMAFit
    offset: float
    singular_values: F64


def _check_known_points(value: Any) -> tuple[tuple[float, float], tuple[float, float]] | None:
    if value is None:
        return None
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        arr = np.zeros(0)
    if arr.shape != (2, 2) or not np.all(np.isfinite(arr)):
        raise InvalidValueError(
            f"The 'known_points' parameter of {_OWNER} must be ((x1, phi(x1)), (x2, phi(x2))), "
            f"four finite numbers. Got {value!r} instead."
        )
    (x1, f1), (x2, f2) = arr.tolist()
    if x1 == x2 or f1 == f2:
        raise InvalidValueError(
            f"The 'known_points' parameter of {_OWNER} must have x1 != x2 and "
            f"phi(x1) != phi(x2). Got {value!r} instead."
        )
    return (x1, f1), (x2, f2)


class HammersteinIdentifier(HyperParameters):
    """Identify a Hammerstein system from input/output data (module docstring).

    Parameters
    ----------
    n_lags : int, default 40
        Length ``L`` of the estimated impulse response (lags ``0 .. L-1``); it
        should cover the linear part's decay.
    order : int or {"bic", "aic"}, default "bic"
        ARMA order ``l`` of the linear part, or the criterion selecting it.
    max_order : int, default 4
        Largest order tried by the criterion; ``n_lags >= 2 max_order + 2``.
    instrument : {"auto", "regression", "input"}, default "auto"
        Instrument of the correlation approach (module docstring).
    kernel : str, default "epanechnikov"
        Kernel of the lag regressions (:data:`flexarm.ident.KERNELS`).
    bandwidth : "auto" or float, default "auto"
        ``h_1`` in units of ``u``; ``"auto"``: half the standard deviation of
        the first ``warmup`` inputs.
    decay : float, default 0.2
        ``h_i = h_1 i**-decay`` (``0 <= decay <= 1``; the paper's conditions
        need ``decay > 0``).
    grid_size : int, default 101
        Points of the grid on which the regressions are kept.
    known_points : ((x1, phi1), (x2, phi2)), optional
        Two points where ``phi`` is known (``x1 != x2``, ``phi1 != phi2``):
        the paper's two-point normalisation. Without them ``phi`` is returned
        up to an affine map (module docstring).
    warmup : int, default 256
        Samples buffered before the grid and ``"auto"`` bandwidth are fixed
        (from those samples); :meth:`fit` needs at least this many.

    Attributes
    ----------
    n_samples_ : int
        Samples seen.
    bandwidth_ : float
        ``h_1`` in use (units of ``u``).
    grid_ : ndarray, shape (g,)
        Grid points where the estimate is defined (points no sample reached
        are dropped).
    shape_ : ndarray, shape (g,)
        The unnormalised shape ``psi`` on ``grid_``.
    nonlinearity_ : ndarray, shape (g,)
        The normalised ``phi`` on ``grid_``.
    impulse_response_ : ndarray, shape (n_lags,)
        ``lambda_0 .. lambda_{L-1}`` from the correlation approach.
    arma_ : ARMA
        Linear part fitted to ``impulse_response_``.
    order_ : int
        Its order ``l``.
    criterion_ : dict of int to float
        Information criterion per order tried.
    offset_ : float
        Output offset added by :meth:`predict` (units of ``y``).
    singular_values_ : ndarray
        Singular values of the weighted lag-regression array; a Hammerstein
        system makes it rank one (``s[1] / s[0]`` small).
    regressions_ : list of SemiRecursiveKernelRegression
        The lag regressions ``m_k`` (grid mode).

    Examples
    --------
    >>> from flexarm.ident import Saturation, simulate_hammerstein
    >>> rng = np.random.default_rng(0)
    >>> u = rng.uniform(-2, 2, 20000)
    >>> y = simulate_hammerstein(Saturation(1.0), [0.5], [1.0, 0.0], u, noise_std=0.1, rng=rng)
    >>> est = HammersteinIdentifier(known_points=((0.0, 0.0), (1.5, 1.0))).fit(u, y)
    >>> np.round(est.impulse_response_[:3], 1)
    array([1. , 0.5, 0.2])
    >>> np.round(est.nonlinearity([-0.5, 0.5, 1.5]), 1)
    array([-0.5,  0.5,  1. ])
    """

    def __init__(
        self,
        n_lags: int = 40,
        order: int | str = "bic",
        max_order: int = 4,
        instrument: str = "auto",
        kernel: str = "epanechnikov",
        bandwidth: float | str = "auto",
        decay: float = 0.2,
        grid_size: int = 101,
        known_points: Any = None,
        warmup: int = 256,
    ) -> None:
        self.n_lags = n_lags
        self.order = order
        self.max_order = max_order
        self.instrument = instrument
        self.kernel = kernel
        self.bandwidth = bandwidth
        self.decay = decay
        self.grid_size = grid_size
        self.known_points = known_points
        self.warmup = warmup

    def _validated(self) -> dict[str, Any]:
        """The hyperparameters, checked (called by the first fit / partial_fit)."""
        p: dict[str, Any] = {}
        p["n_lags"] = check_int(self.n_lags, "n_lags", _OWNER, minimum=1)
        p["max_order"] = check_int(self.max_order, "max_order", _OWNER, minimum=0)
        if isinstance(self.order, str):
            p["order"] = check_option(self.order, "order", _OWNER, _CRITERIA)
            top = p["max_order"]
        else:
            p["order"] = check_int(self.order, "order", _OWNER, minimum=0)
            top = p["order"]
        if p["n_lags"] < 2 * top + 2:
            raise InvalidValueError(
                f"The 'n_lags' parameter of {_OWNER} must be >= 2 * order + 2 = {2 * top + 2} "
                f"to fit ARMA order {top}. Got {p['n_lags']} instead."
            )
        p["instrument"] = check_option(self.instrument, "instrument", _OWNER, _INSTRUMENTS)
        p["kernel"] = check_option(self.kernel, "kernel", _OWNER, KERNELS)
        if isinstance(self.bandwidth, str):
            check_option(self.bandwidth, "bandwidth", _OWNER, ("auto",))
            p["bandwidth"] = None
        else:
            p["bandwidth"] = check_real(self.bandwidth, "bandwidth", _OWNER, positive=True)
        decay = check_real(self.decay, "decay", _OWNER, nonnegative=True)
        if decay > 1.0:
            raise InvalidValueError(
                f"The 'decay' parameter of {_OWNER} must be <= 1. Got {decay} instead."
            )
        p["decay"] = decay
        p["grid_size"] = check_int(self.grid_size, "grid_size", _OWNER, minimum=8)
        p["known_points"] = _check_known_points(self.known_points)
        p["warmup"] = check_int(self.warmup, "warmup", _OWNER, minimum=8)
        return p

    # ---------------------------------------------------------------- fitting

    def _check_uy(self, u: ArrayLike, y: ArrayLike) -> tuple[F64, F64]:
        arrays = []
        for name, value in (("u", u), ("y", y)):
            arr = check_array(value, name, _OWNER)
            if arr.dtype.kind == "c":
                raise InvalidTypeError(
                    f"The '{name}' parameter of {_OWNER} must be real. Got complex."
                )
            if arr.ndim != 1:
                raise InvalidValueError(
                    f"The '{name}' parameter of {_OWNER} must be of shape (n,). "
                    f"Got shape {arr.shape} instead."
                )
            arrays.append(np.ascontiguousarray(arr, dtype=np.float64))
        ua, ya = arrays
        if ya.shape[0] != ua.shape[0]:
            raise InvalidValueError(
                f"The 'y' parameter of {_OWNER} must have the length of u ({ua.shape[0]}). "
                f"Got length {ya.shape[0]} instead."
            )
        return ua, ya

    def _reset(self) -> None:
        for name in [k for k in vars(self) if k.endswith("_") and not k.startswith("__")]:
            delattr(self, name)
        for name in (
            "_params",
            "_frozen",
            "_buffer_u",
            "_buffer_y",
            "_tail",
            "_sums",
            "_grid_all",
            "_cache",
        ):
            self.__dict__.pop(name, None)

    def fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        """Forget any previous state and identify the system from one record.

        Parameters
        ----------
        u : array_like, shape (n,)
            Input ``X_n`` (i.i.d. for the correlation approach to be exact), any unit.
        y : array_like, shape (n,)
            Output ``Y_n``, any unit; ``n >= warmup`` and ``n >= 4 n_lags``.

        Returns
        -------
        self
        """
        ua, ya = self._check_uy(u, y)
        params = self._validated()
        need = max(params["warmup"], 4 * params["n_lags"])
        if ua.shape[0] < need:
            raise InvalidValueError(
                f"The 'u' parameter of {_OWNER} must hold at least {need} samples "
                f"(max(warmup, 4 * n_lags)). Got {ua.shape[0]} instead."
            )
        if np.ptp(ya) == 0.0:
            raise InvalidValueError(
                f"The 'y' parameter of {_OWNER} must vary with the input. Got a constant output."
            )
        self._reset()
        self.partial_fit(ua, ya)
        self._solution()
        return self

    def partial_fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        """Add a chunk of the record; chunks give bit for bit what one :meth:`fit` gives.

        The hyperparameters are fixed by the first call; the first ``warmup``
        samples are buffered until the grid and bandwidth can be set.

        Parameters
        ----------
        u : array_like, shape (n,)
            Next inputs.
        y : array_like, shape (n,)
            Next outputs.

        Returns
        -------
        self
        """
        ua, ya = self._check_uy(u, y)
        if not hasattr(self, "_params"):
            self._params = self._validated()
            self._frozen = self.get_params()
            self._buffer_u: list[F64] = []
            self._buffer_y: list[F64] = []
            self._sums = np.zeros(2)
            self.n_samples_ = 0
        else:
            now = self.get_params()
            changed = sorted(k for k in now if repr(now[k]) != repr(self._frozen[k]))
            if changed:
                raise InvalidValueError(
                    f"The {changed} parameter(s) of {_OWNER} changed since the first "
                    "partial_fit. Got new values instead; call fit to start again."
                )
        self.__dict__.pop("_cache", None)
        if ua.shape[0] == 0:
            return self
        _running_sums(ya, self._sums)
        self.n_samples_ += ua.shape[0]
        if not hasattr(self, "regressions_"):
            self._buffer_u.append(ua)
            self._buffer_y.append(ya)
            if self.n_samples_ < self._params["warmup"]:
                return self
            ua = np.concatenate(self._buffer_u)
            ya = np.concatenate(self._buffer_y)
            self._buffer_u, self._buffer_y = [], []
            self._start(ua[: self._params["warmup"]])
        self._add(ua, ya)
        return self

    def _start(self, u0: F64) -> None:
        p = self._params
        spread = float(np.std(u0))
        if not spread > 0.0:
            raise InvalidValueError(
                f"The 'u' parameter of {_OWNER} must vary (its spread sets the grid and the "
                f"bandwidth). Got a constant input over the first {u0.shape[0]} samples instead."
            )
        lo, hi = float(np.min(u0)), float(np.max(u0))
        margin = 0.1 * (hi - lo)
        grid = np.linspace(lo - margin, hi + margin, p["grid_size"])
        h1 = 0.5 * spread if p["bandwidth"] is None else p["bandwidth"]
        self.bandwidth_ = h1
        self._grid_all = grid
        self.regressions_ = [
            SemiRecursiveKernelRegression(
                kernel=p["kernel"], bandwidth=h1, decay=p["decay"], grid=grid
            )
            for _ in range(p["n_lags"])
        ]
        self._tail = np.zeros(0)

    def _add(self, u: F64, y: F64) -> None:
        L = self._params["n_lags"]
        t = self._tail.shape[0]
        ext = np.concatenate([self._tail, u])
        m = u.shape[0]
        for k, reg in enumerate(self.regressions_):
            j0 = max(0, k - t)
            if j0 >= m:
                continue
            reg.partial_fit(ext[t + j0 - k : t + m - k], y[j0:])
        self._tail = ext[-(L - 1) :].copy() if L > 1 else np.zeros(0)

    # ---------------------------------------------------------------- solution

    def _check_fitted(self) -> None:
        if (
            not hasattr(self, "regressions_")
            or self.regressions_[-1].__dict__.get("n_samples_", 0) < 2
        ):
            raise NotFittedError(
                f"This {_OWNER} instance is not fitted yet (or has seen fewer than "
                "warmup + n_lags samples). Call 'fit' or 'partial_fit' with more data "
                "before using this estimator."
            )

    def _solution(self) -> _Solution:
        self._check_fitted()
        cached = self.__dict__.get("_cache")
        if cached is not None:
            sol: _Solution = cached
            return sol
        p = self._params
        num = np.array([r.numerator_ for r in self.regressions_])
        den = np.array([r.denominator_ for r in self.regressions_])
        valid = np.all(den > 0.0, axis=0)
        if np.count_nonzero(valid) < 2:
            raise InvalidValueError(
                f"The 'u' parameter of {_OWNER} must spread over the grid. Got samples "
                "reaching fewer than 2 grid points instead."
            )
        grid = self._grid_all[valid]
        m = num[:, valid] / den[:, valid]
        w = den[0, valid] / np.sum(den[0, valid])
        centred = m - (m @ w)[:, None]
        sq = np.sqrt(w)
        svals = np.linalg.svd(centred * sq[None, :], compute_uv=False)
        instrument = p["instrument"]
        if instrument == "auto":
            left, s, _ = np.linalg.svd(centred * sq[None, :], full_matrices=False)
            psi = (left[:, 0] @ centred) / s[0] if s[0] > 0 else np.zeros(grid.shape[0])
        elif instrument == "regression":
            psi = centred[0]
        else:
            psi = grid - grid @ w
        lags = centred @ (w * psi)
        energy = float(lags @ lags)
        if not energy > 0.0 or not np.isfinite(energy):
            raise InvalidValueError(
                f"The 'y' parameter of {_OWNER} must depend on u through the chosen instrument "
                f"({instrument!r}). Got no correlation instead (try instrument='auto')."
            )
        shape = (lags @ centred) / energy
        known = p["known_points"]
        if known is None:
            k = int(np.argmax(np.abs(lags)))
            scale = float(lags[k])
            impulse = lags / scale
            phi = shape * scale
        else:
            (x1, f1), (x2, f2) = known
            for x in (x1, x2):
                if not grid[0] <= x <= grid[-1]:
                    raise InvalidValueError(
                        f"The 'known_points' parameter of {_OWNER} must lie within the input's "
                        f"range [{grid[0]:.6g}, {grid[-1]:.6g}]. Got x = {x} instead."
                    )
            s1, s2 = np.interp([x1, x2], grid, shape)
            if s1 == s2:
                raise InvalidValueError(
                    f"The 'known_points' parameter of {_OWNER} must name points where the "
                    f"estimate differs. Got equal estimates at x1 = {x1} and x2 = {x2} instead."
                )
            d1, alpha = two_point_normalisation(float(s1), float(s2), f1, f2)
            phi = (shape - alpha) / d1
            impulse = lags * d1
        arma = arma_from_impulse_response(impulse, order=p["order"], max_order=p["max_order"])
        mean_y = float(self._sums[0] / self.n_samples_)
        offset = mean_y - arma.model.dc_gain * float(phi @ w)
        sol = _Solution(lags, shape, grid, w, impulse, phi, arma, offset, svals)
        self._cache = sol
        return sol

    @property
    def impulse_response_(self) -> F64:
        """``lambda_0 .. lambda_{L-1}`` (correlation approach), shape (n_lags,)."""
        return self._solution().impulse.copy()

    @property
    def nonlinearity_(self) -> F64:
        """The identified ``phi`` on :attr:`grid_`, shape (g,)."""
        return self._solution().nonlinearity.copy()

    @property
    def shape_(self) -> F64:
        """The unnormalised shape ``psi`` on :attr:`grid_`, shape (g,)."""
        return self._solution().shape.copy()

    @property
    def grid_(self) -> F64:
        """Grid points (units of ``u``) where the estimate is defined, shape (g,)."""
        return self._solution().grid.copy()

    @property
    def input_weights_(self) -> F64:
        """Kernel estimate of the input distribution on :attr:`grid_` (sums to 1), shape (g,)."""
        return self._solution().weights.copy()

    @property
    def arma_(self) -> ARMA:
        """The ARMA model of the linear part."""
        return self._solution().arma.model

    @property
    def order_(self) -> int:
        """The selected ARMA order ``l``."""
        return self._solution().arma.order

    @property
    def criterion_(self) -> dict[int, float]:
        """Information criterion of each order tried."""
        return dict(self._solution().arma.criterion)

    @property
    def offset_(self) -> float:
        """Output offset added by :meth:`predict`, units of ``y``."""
        return self._solution().offset

    @property
    def singular_values_(self) -> F64:
        """Singular values of the weighted lag-regression array (rank one if Hammerstein)."""
        return self._solution().singular_values.copy()

    def nonlinearity(self, x: ArrayLike) -> F64:
        """The identified ``phi`` at ``x`` (linear interpolation on the grid, held beyond it).

        Parameters
        ----------
        x : array_like, any shape
            Inputs (units of ``u``).

        Returns
        -------
        ndarray, same shape as ``x``
        """
        sol = self._solution()
        xa = check_array(x, "x", f"{_OWNER}.nonlinearity")
        out: F64 = np.interp(xa, sol.grid, sol.nonlinearity)
        return out

    def predict(self, u: ArrayLike) -> F64:
        """Free-run output of the identified model for the input ``u`` (from rest).

        ``y_hat = ARMA(phi_hat(u)) + offset_``.

        Parameters
        ----------
        u : array_like, shape (n,)
            Input sequence (units of ``u``).

        Returns
        -------
        ndarray, shape (n,)
            Predicted output (units of ``y``).
        """
        sol = self._solution()
        ua = check_array(u, "u", f"{_OWNER}.predict", shape=(-1,))
        w = np.interp(ua, sol.grid, sol.nonlinearity)
        out: F64 = sol.arma.model.filter(w) + sol.offset
        return out

    def score(self, u: ArrayLike, y: ArrayLike) -> float:
        """Fit in percent of :meth:`predict` on ``(u, y)`` (:func:`fit_percent`)."""
        ua, ya = self._check_uy(u, y)
        return fit_percent(ya, self.predict(ua))
