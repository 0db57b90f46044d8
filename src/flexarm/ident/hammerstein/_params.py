"""The hyperparameters of :class:`~flexarm.ident.HammersteinIdentifier`, and its choice of path.

:func:`validate` checks the hyperparameters when a fit starts (the constructor
only stores them, as scikit-learn requires); every error names the parameter.
:func:`choose_path` applies ``method``: ``"auto"`` takes the white-input path
when the whiteness test passes and the record is long enough for it.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from ..._types import F64
from ..._validation import check_int, check_option, check_real
from ...errors import InvalidValueError
from ..options import INSTRUMENTS, KERNELS, METHODS, ORDER_RULES
from ..regression.bandwidth import as_rule
from .linear import MIN_SAMPLES, check_fraction
from .solution import check_known_points
from .white.lags import WHITE_MAX_ORDER
from .whiteness import WhitenessReport, whiteness_test

__all__ = ["CORRELATED_MAX_ORDER", "check_length", "choose_path", "correlated_orders", "validate"]

_OWNER = "HammersteinIdentifier"

#: ``max_order=None``: the correlated path's and the linear baseline's largest order.
CORRELATED_MAX_ORDER = 10


def validate(given: Mapping[str, Any]) -> dict[str, Any]:
    """The hyperparameters ``given`` (``get_params()``), checked by the first fit or partial_fit."""
    p: dict[str, Any] = {}
    p["n_lags"] = check_int(given["n_lags"], "n_lags", _OWNER, minimum=1)
    p["max_order"] = (
        None
        if given["max_order"] is None
        else check_int(given["max_order"], "max_order", _OWNER, minimum=0)
    )
    if isinstance(given["order"], str):
        p["order"] = check_option(given["order"], "order", _OWNER, ORDER_RULES)
        top = WHITE_MAX_ORDER if p["max_order"] is None else p["max_order"]
    else:
        p["order"] = check_int(given["order"], "order", _OWNER, minimum=0)
        top = p["order"]
    if p["n_lags"] < 2 * top + 2:
        raise InvalidValueError(
            f"The 'n_lags' parameter of {_OWNER} must be >= 2 * order + 2 = {2 * top + 2} "
            f"to fit ARMA order {top}. Got {p['n_lags']} instead."
        )
    p["instrument"] = check_option(given["instrument"], "instrument", _OWNER, INSTRUMENTS)
    p["kernel"] = check_option(given["kernel"], "kernel", _OWNER, KERNELS)
    rule = as_rule(given["bandwidth"], _OWNER)
    p["bandwidth"] = (
        rule
        if rule is not None
        else check_real(given["bandwidth"], "bandwidth", _OWNER, positive=True)
    )
    decay = check_real(given["decay"], "decay", _OWNER, nonnegative=True)
    if decay > 1.0:
        raise InvalidValueError(
            f"The 'decay' parameter of {_OWNER} must be <= 1. Got {decay} instead."
        )
    p["decay"] = decay
    p["grid_size"] = check_int(given["grid_size"], "grid_size", _OWNER, minimum=8)
    p["known_points"] = check_known_points(given["known_points"], _OWNER)
    p["warmup"] = check_int(given["warmup"], "warmup", _OWNER, minimum=8)
    p["method"] = check_option(given["method"], "method", _OWNER, METHODS)
    if isinstance(given["n_knots"], str):
        check_option(given["n_knots"], "n_knots", _OWNER, ("auto",))
        p["n_knots"] = None
    else:
        p["n_knots"] = check_int(given["n_knots"], "n_knots", _OWNER, minimum=2)
    p["validation_fraction"] = check_fraction(given["validation_fraction"], _OWNER)
    alpha = check_real(given["alpha"], "alpha", _OWNER, positive=True)
    if not alpha < 1.0:
        raise InvalidValueError(
            f"The 'alpha' parameter of {_OWNER} must be in (0, 1). Got {alpha} instead."
        )
    p["alpha"] = alpha
    return p


def choose_path(p: Mapping[str, Any], u: F64) -> tuple[str, str, WhitenessReport]:
    """The path, why, and the input's whiteness (:mod:`flexarm.ident.hammerstein.identifier`)."""
    white = whiteness_test(u, alpha=p["alpha"])
    need = max(p["warmup"], 4 * p["n_lags"])
    n = u.shape[0]
    if p["method"] == "white":
        return "white", f"method='white' was asked for; {white.reason}", white
    if p["method"] == "correlated":
        return "correlated", f"method='correlated' was asked for; {white.reason}", white
    if not white.white:
        return "correlated", f"{white.reason}: the correlated-input path", white
    if n < need:
        reason = f"{white.reason}, but {n} samples are too few for the white path (< {need})"
        return "correlated", f"{reason}: the correlated-input path", white
    return "white", f"{white.reason}: the correlation approach (the paper's)", white


def correlated_orders(p: Mapping[str, Any], baseline: bool = False) -> tuple[int | None, int]:
    """``(order or None to choose it, largest order)`` of the correlated path.

    With ``baseline``, for the linear baseline of either path (no check of ``order``).
    """
    top = CORRELATED_MAX_ORDER if p["max_order"] is None else max(1, p["max_order"])
    if baseline:
        return None, top
    order = p["order"]
    if order in ("bic", "aic"):
        raise InvalidValueError(
            f"The 'order' parameter of {_OWNER} must be 'auto' or an integer >= 1 on the "
            "correlated-input path (BIC and AIC choose the white path's ARMA order). "
            f"Got {order!r} instead."
        )
    if order == 0 or p["max_order"] == 0:
        raise InvalidValueError(
            f"The 'order' parameter of {_OWNER} must be >= 1 on the correlated-input "
            f"path (with max_order >= 1). Got order={order!r}, max_order={p['max_order']!r}."
        )
    return (None if order == "auto" else int(order)), top


def check_length(p: Mapping[str, Any], n: int) -> None:
    """A record of ``n`` samples is long enough for :meth:`fit` (``MIN_SAMPLES``, and
    ``max(warmup, 4 n_lags)`` when the white path is asked for)."""
    minimum = MIN_SAMPLES
    why = "held-out validation of the structure and of the linear baseline"
    if p["method"] == "white" and max(p["warmup"], 4 * p["n_lags"]) > MIN_SAMPLES:
        minimum, why = max(p["warmup"], 4 * p["n_lags"]), "max(warmup, 4 * n_lags)"
    if n < minimum:
        raise InvalidValueError(
            f"The 'u' parameter of {_OWNER} must hold at least {minimum} samples "
            f"({why}). Got {n} instead."
        )
