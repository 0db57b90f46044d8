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

3. **ARMA coefficients** from the impulse response
   (:func:`~flexarm.ident.arma.arma_from_impulse_response`): for each order
   ``l = 0 .. max_order`` (the paper's ``ARMA(l, l)``), Prony's start refined
   by nonlinear least squares; the order minimising BIC (by default) is kept.

Steps 1-3 are :func:`flexarm.ident.correlation.solve`.

Defaults and scale
------------------
The default bandwidth is ``Silverman(0.55)`` (:mod:`flexarm.ident.bandwidth`):
0.55 times Silverman's rule of thumb evaluated on the first ``warmup`` inputs,
``h_1 = 0.55 * 0.9 min(sd, IQR/1.34) warmup**(decay - 1/5)`` — with the default
``decay = 0.2``, ``h_1 = 0.495 min(sd, IQR/1.34)`` and every ``h_i`` is 0.55
times the rule for the first ``i`` samples. The factor below 1 keeps jumps of
``phi`` (quantizers, dead zones with a jump) resolved; ``bandwidth="silverman"``
gives the rule itself. The grid spans the first ``warmup`` inputs' range
widened by 10 % on each side: nothing depends on the units of ``u`` or ``y``.
Outside the grid the estimate is held at its end values.

Streaming
---------
The state is the ``n_lags`` grid-mode regressions (running sums), the last
``n_lags - 1`` inputs and sequential running sums of ``y``; the first
``warmup`` samples are buffered until the scale is known. Samples enter every
sum in arrival order, so :meth:`~HammersteinIdentifier.partial_fit` on chunks
equals :meth:`~HammersteinIdentifier.fit` on the whole record bit for bit.
The impulse response, nonlinearity and ARMA model are derived from the state
when first asked for after an update. :meth:`~HammersteinIdentifier.save`
writes that state (the lag regressions through their own state description,
:mod:`flexarm.ident.accumulators`) and :meth:`~HammersteinIdentifier.load`
resumes it exactly.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any, Self

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._io import atomic_path
from .._validation import check_array, check_int, check_option, check_real
from ..errors import InvalidTypeError, InvalidValueError
from ._params import HyperParameters
from .accumulators import State
from .arma import ARMAFit, arma_from_impulse_response
from .bandwidth import Silverman, as_rule
from .correlation import (
    KnownPoints,
    Solution,
    check_known_points,
    solve,
    two_point_normalisation,
)
from .kernels import KERNELS
from .lags import LagRegressions
from .options import CRITERIA, INSTRUMENTS
from .regression import NotFittedError, SemiRecursiveKernelRegression
from .systems import ARMA, fit_percent

__all__ = [
    "DEFAULT_BANDWIDTH",
    "ARMAFit",
    "HammersteinIdentifier",
    "arma_from_impulse_response",
    "fit_percent",
    "two_point_normalisation",
]

F64 = NDArray[np.float64]
_OWNER = "HammersteinIdentifier"
_FORMAT = 1  # version of the save() file layout

#: The default bandwidth: 0.55 times Silverman's rule on the first ``warmup`` inputs.
DEFAULT_BANDWIDTH = Silverman(0.55)


def _plain(value: Any) -> Any:
    """NumPy scalars and arrays as plain Python values, for JSON."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


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
    bandwidth : float, "silverman" or Silverman, default Silverman(0.55)
        ``h_1`` in units of ``u``, or a rule evaluated on the first ``warmup``
        inputs (:mod:`flexarm.ident.bandwidth`; module docstring).
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
        Samples buffered before the grid and a rule's bandwidth are fixed
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
        bandwidth: float | str | Silverman = DEFAULT_BANDWIDTH,
        decay: float = 0.2,
        grid_size: int = 101,
        known_points: KnownPoints | None = None,
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
            p["order"] = check_option(self.order, "order", _OWNER, CRITERIA)
            top = p["max_order"]
        else:
            p["order"] = check_int(self.order, "order", _OWNER, minimum=0)
            top = p["order"]
        if p["n_lags"] < 2 * top + 2:
            raise InvalidValueError(
                f"The 'n_lags' parameter of {_OWNER} must be >= 2 * order + 2 = {2 * top + 2} "
                f"to fit ARMA order {top}. Got {p['n_lags']} instead."
            )
        p["instrument"] = check_option(self.instrument, "instrument", _OWNER, INSTRUMENTS)
        p["kernel"] = check_option(self.kernel, "kernel", _OWNER, KERNELS)
        rule = as_rule(self.bandwidth, _OWNER)
        p["bandwidth"] = (
            rule
            if rule is not None
            else check_real(self.bandwidth, "bandwidth", _OWNER, positive=True)
        )
        decay = check_real(self.decay, "decay", _OWNER, nonnegative=True)
        if decay > 1.0:
            raise InvalidValueError(
                f"The 'decay' parameter of {_OWNER} must be <= 1. Got {decay} instead."
            )
        p["decay"] = decay
        p["grid_size"] = check_int(self.grid_size, "grid_size", _OWNER, minimum=8)
        p["known_points"] = check_known_points(self.known_points, _OWNER)
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
        for name in ("_params", "_frozen", "_lags", "_cache"):
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
        if "_params" not in self.__dict__:
            self._params = self._validated()
            self._frozen = self.get_params()
            self._lags = LagRegressions(self._params, _OWNER)
        else:
            now = self.get_params()
            changed = sorted(k for k in now if repr(now[k]) != repr(self._frozen[k]))
            if changed:
                raise InvalidValueError(
                    f"The {changed} parameter(s) of {_OWNER} changed since the first "
                    "partial_fit. Got new values instead; call fit to start again."
                )
        self.__dict__.pop("_cache", None)
        self._lags.add_chunk(ua, ya)
        return self

    @property
    def n_samples_(self) -> int:
        """Samples seen."""
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None:
            raise NotFittedError(f"This {_OWNER} instance is not fitted yet.")
        return lags.n_samples

    def _started(self, name: str) -> LagRegressions:
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None or lags.regressions is None:
            raise NotFittedError(
                f"This {_OWNER} instance has no {name} yet (fewer than warmup samples seen)."
            )
        return lags

    @property
    def bandwidth_(self) -> float:
        """``h_1`` in use (units of ``u``), fixed after the first ``warmup`` samples."""
        return self._started("bandwidth_").bandwidth

    @property
    def regressions_(self) -> list[SemiRecursiveKernelRegression]:
        """The lag regressions ``m_k``, ``k = 0 .. n_lags - 1`` (grid mode)."""
        regs = self._started("regressions_").regressions
        assert regs is not None
        return regs

    # ---------------------------------------------------------------- solution

    def _check_fitted(self) -> LagRegressions:
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None or not lags.ready:
            raise NotFittedError(
                f"This {_OWNER} instance is not fitted yet (or has seen fewer than "
                "warmup + n_lags samples). Call 'fit' or 'partial_fit' with more data "
                "before using this estimator."
            )
        return lags

    def _solution(self) -> Solution:
        lags = self._check_fitted()
        cached: Solution | None = self.__dict__.get("_cache")
        if cached is not None:
            return cached
        p = self._params
        sol = solve(
            *lags.lag_sums(),
            lags.grid,
            instrument=p["instrument"],
            known_points=p["known_points"],
            order=p["order"],
            max_order=p["max_order"],
            mean_y=float(lags.sums[0] / lags.n_samples),
            owner=_OWNER,
        )
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

    # ---------------------------------------------------------------- persistence

    def _state(self) -> State:
        """The one state description: hyperparameters (JSON) and the lag regressions' state."""
        lags: LagRegressions | None = self.__dict__.get("_lags")
        if lags is None:
            raise NotFittedError(
                f"This {_OWNER} instance is not fitted yet. Call 'fit' or 'partial_fit' "
                "before saving it."
            )
        params = dict(self._frozen)
        if isinstance(params["bandwidth"], Silverman):
            params["bandwidth"] = {"silverman": params["bandwidth"].factor}
        header: State = {
            "format": np.array(_FORMAT),
            "estimator": np.array(_OWNER),
            "params": np.array(json.dumps(params, default=_plain)),
        }
        return {**header, **lags.state()}

    @classmethod
    def _from_state(cls, data: Mapping[str, NDArray[Any]]) -> Self:
        if int(data.get("format", -1)) != _FORMAT or str(data.get("estimator")) != _OWNER:
            raise InvalidValueError(
                f"The 'path' parameter of {_OWNER}.load must name a file saved by "
                f"{_OWNER}.save. Got {data.get('estimator', 'another file')!s} instead."
            )
        params = json.loads(str(data["params"]))
        if isinstance(params["bandwidth"], dict):
            params["bandwidth"] = Silverman(float(params["bandwidth"]["silverman"]))
        if params["known_points"] is not None:
            (x1, f1), (x2, f2) = params["known_points"]
            params["known_points"] = ((x1, f1), (x2, f2))
        est = cls(**params)
        est._params = est._validated()
        est._frozen = est.get_params()
        est._lags = LagRegressions.from_state(est._params, _OWNER, data)
        return est

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write the hyperparameters and the streaming state to ``path`` (NumPy ``.npz``).

        Works at any point after the first :meth:`fit` or :meth:`partial_fit`
        (also during the warmup); :meth:`load` resumes exactly, so
        ``partial_fit`` after ``load`` gives bit for bit what it would have
        given without stopping. Plain arrays only (no pickle), written
        atomically as given (no suffix added).

        Parameters
        ----------
        path : str or os.PathLike
            Destination file.
        """
        arrays: dict[str, Any] = self._state()
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Self:
        """Read an identifier written by :meth:`save`.

        Parameters
        ----------
        path : str or os.PathLike
            File written by :meth:`save`.

        Returns
        -------
        HammersteinIdentifier
            With the state it had when saved.
        """
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        return cls._from_state(data)
