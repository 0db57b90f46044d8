"""Checks of the kernel estimators' hyperparameters and samples, into a :class:`Smoothing`.

Called by :meth:`fit`/:meth:`partial_fit` of the estimators in
:mod:`flexarm.ident.regression.estimators` (the constructors only store their arguments,
as scikit-learn requires). Every error names the parameter and the estimator.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..._types import F64
from ..._validation import check_array, check_option, check_real
from ...errors import InvalidTypeError, InvalidValueError
from ..options import BINNABLE
from .accumulators import Smoothing
from .accumulators.base import CALLABLE
from .accumulators.series import auto_series
from .bandwidth import as_rule
from .kernels import KERNELS

__all__ = ["BIN_MAX", "BIN_MIN", "check_X", "check_Xy", "smoothing"]


#: Allowed relative bin widths ``r = delta / h`` of binned mode.
BIN_MIN, BIN_MAX = 1e-4, 0.5


def _fail(owner: str, name: str, expected: str, got: str) -> InvalidValueError:
    return InvalidValueError(
        f"The '{name}' parameter of {owner} must be {expected}. Got {got} instead."
    )


def _real(arr: NDArray[Any], name: str, owner: str) -> None:
    if arr.dtype.kind == "c":
        raise InvalidTypeError(
            f"The '{name}' parameter of {owner} must be real. Got complex instead."
        )


def check_X(X: ArrayLike, owner: str, name: str = "X") -> F64:
    """``X`` as a C-contiguous float array of shape ``(n, d)`` (``(n,)`` means ``d = 1``)."""
    arr = check_array(X, name, owner)
    _real(arr, name, owner)
    if arr.ndim == 1:
        arr = arr[:, None]
    if arr.ndim != 2:
        raise _fail(owner, name, "of shape (n,) or (n, d)", f"shape {arr.shape}")
    if arr.shape[1] < 1:
        raise _fail(owner, name, "of at least one column", f"shape {arr.shape}")
    return np.ascontiguousarray(arr, dtype=np.float64)


def check_Xy(X: ArrayLike, y: ArrayLike, owner: str) -> tuple[F64, F64]:
    """Samples: ``X`` of shape ``(n, d)`` and ``y`` of shape ``(n,)``, ``n >= 1``, finite."""
    Xa = check_X(X, owner)
    ya = check_array(y, "y", owner)
    _real(ya, "y", owner)
    if ya.ndim != 1:
        raise _fail(owner, "y", "of shape (n,)", f"shape {ya.shape}")
    if ya.shape[0] != Xa.shape[0]:
        raise _fail(owner, "y", f"of length {Xa.shape[0]} (the rows of X)", f"length {ya.shape[0]}")
    if Xa.shape[0] == 0:
        raise _fail(owner, "X", "at least one sample", "0 samples")
    return Xa, np.ascontiguousarray(ya, dtype=np.float64)


def _kernel(value: Any, owner: str) -> int:
    if callable(value):
        return CALLABLE
    return KERNELS.index(check_option(value, "kernel", owner, KERNELS))


def _decay(params: Mapping[str, Any], d: int, owner: str, fixed: float | None) -> float:
    if fixed is not None:
        return fixed
    decay = check_real(params.get("decay", 0.0), "decay", owner, nonnegative=True)
    if decay * d > 1.0 + 1e-12:
        raise _fail(
            owner,
            "decay",
            f"<= 1/d = {1.0 / d:.6g} for d = {d} (sum of h_i**d must diverge)",
            repr(decay),
        )
    return decay


def _bandwidth(value: Any, X: F64, decay: float, owner: str) -> F64:
    d = X.shape[1]
    rule = as_rule(value, owner)
    if rule is not None:
        return rule(X, decay, owner=owner)
    if np.ndim(value) == 0:
        return np.full(d, check_real(value, "bandwidth", owner, positive=True))
    arr = check_array(value, "bandwidth", owner, shape=(-1,))
    _real(arr, "bandwidth", owner)
    if arr.shape[0] != d:
        raise _fail(
            owner,
            "bandwidth",
            f"a scalar or of shape ({d},) for {d}-dimensional X",
            f"shape {arr.shape}",
        )
    if not np.all(arr > 0.0):
        raise _fail(owner, "bandwidth", "> 0", repr(arr))
    return np.ascontiguousarray(arr, dtype=np.float64)


def _binned(value: Any, code: int, d: int, has_grid: bool, owner: str) -> float | None:
    if value is None:
        return None
    r = check_real(value, "binned", owner, positive=True)
    if not BIN_MIN <= r <= BIN_MAX:
        raise _fail(
            owner, "binned", f"None or a relative bin width in [{BIN_MIN:g}, {BIN_MAX:g}]", repr(r)
        )
    if not has_grid:
        raise _fail(owner, "binned", "None in exact mode (binning needs a grid)", repr(r))
    if d != 1:
        raise _fail(owner, "binned", f"None for d = {d} (binning is one-dimensional)", repr(r))
    name = "a callable" if code == CALLABLE else repr(KERNELS[code])
    if code == CALLABLE or KERNELS[code] not in BINNABLE:
        raise _fail(
            owner, "binned", f"None with kernel {name} (binnable kernels: {BINNABLE})", repr(r)
        )
    return r


def _series(
    value: Any,
    code: int,
    decay: float,
    binned: float | None,
    grid: F64 | None,
    bw: F64,
    owner: str,
) -> bool:
    """``series`` resolved: ``"auto"`` is the series where it applies and is faster."""
    d = bw.shape[0]
    if isinstance(value, str):
        if value != "auto":
            raise _fail(owner, "series", "True, False or 'auto'", repr(value))
        applies = code == 0 and d == 1 and decay == 0.0 and binned is None
        return applies and auto_series(grid, float(bw[0]))
    if not isinstance(value, bool | np.bool_):
        raise InvalidTypeError(
            f"The 'series' parameter of {owner} must be a bool or 'auto'. Got {value!r} instead."
        )
    if not value:
        return False
    if code != 0:
        raise _fail(owner, "series", "False unless kernel='gaussian'", "True")
    if d != 1:
        raise _fail(owner, "series", f"False for d = {d} (the series is one-dimensional)", "True")
    if decay != 0.0:
        raise _fail(owner, "series", "False unless decay = 0 (one bandwidth)", "True")
    if binned is not None:
        raise _fail(owner, "series", "False in binned mode (choose one)", "True")
    return True


def smoothing(
    params: Mapping[str, Any],
    owner: str,
    *,
    recursive: bool,
    fixed_decay: float | None,
    X: F64 | None = None,
    d: int | None = None,
    bandwidth: F64 | None = None,
    source: str | None = None,
) -> Smoothing:
    """Validate the hyperparameters ``params`` into the estimate's :class:`Smoothing`.

    Parameters
    ----------
    params : mapping
        ``get_params()`` of the estimator (``kernel``, ``bandwidth``, ``decay``,
        ``grid``, ``binned``, ``series``).
    owner : str
        The estimator's name, for the error messages.
    recursive : bool
        Devroye–Wagner weights.
    fixed_decay : float or None
        The decay of an estimator without a ``decay`` parameter.
    X : ndarray, shape (n, d), optional
        The first samples: they give ``d`` and feed a bandwidth rule.
    d : int, optional
        Input dimension when ``X`` is not given (with ``bandwidth``).
    bandwidth : ndarray, shape (d,), optional
        The resolved ``h_1`` (when restoring a saved state: no rule is evaluated).
    source : str, optional
        With ``d`` and without ``X`` or ``bandwidth``: what the samples come
        from (e.g. "a Dask array"), named when a bandwidth rule, which needs
        every sample at once, is refused.
    """
    dim = X.shape[1] if X is not None else d
    assert dim is not None
    code = _kernel(params["kernel"], owner)
    decay = _decay(params, dim, owner, fixed_decay)
    if bandwidth is None and X is None:
        value = params["bandwidth"]
        if as_rule(value, owner) is not None:
            raise _fail(
                owner,
                "bandwidth",
                f"a number to fit from {source} (a rule such as 'silverman' needs every "
                "sample at once; compute it with silverman_bandwidth(X_part, decay, n=n_total) "
                "and pass the value)",
                repr(value),
            )
        bw = _bandwidth(value, np.zeros((1, dim)), decay, owner)
    elif bandwidth is None:
        assert X is not None
        bw = _bandwidth(params["bandwidth"], X, decay, owner)
    else:
        bw = np.ascontiguousarray(bandwidth, dtype=np.float64).reshape(dim)
    grid = None
    if params["grid"] is not None:
        grid = check_X(params["grid"], owner, "grid")
        if grid.shape[1] != dim:
            raise _fail(owner, "grid", f"of {dim} column(s) like X", f"{grid.shape[1]} column(s)")
        if grid.shape[0] == 0:
            raise _fail(owner, "grid", "non-empty", "0 points")
        grid = grid.copy()
    r = _binned(params.get("binned"), code, dim, grid is not None, owner)
    series = _series(params.get("series", False), code, decay, r, grid, bw, owner)
    setup = Smoothing(owner, params["kernel"], code, bw, decay, recursive, grid, r, series)
    if code == CALLABLE:  # fail early on a kernel that returns the wrong shape
        probe = np.zeros((3, dim))
        probe[1:] = [[0.5], [-2.0]]
        setup.callable_weights(probe[:1], probe, np.ones((3, dim)), np.ones(3))
    return setup
