"""The fitted state of the kernel regression estimators, and its plain arrays.

:class:`RegressionState` is what a fit leaves: the hyperparameters it froze and the
accumulator of the mode (:mod:`~flexarm.ident.regression.accumulators`), which keeps
the validated :class:`~flexarm.ident.regression.accumulators.Smoothing` and the
streaming sums. As plain arrays (``to_arrays``, the ``.npz`` file of ``save``, no
pickle) it is one description: the hyperparameters (``format``, ``estimator``,
``kernel``, ``bandwidth`` — the value given, or a rule's value with
``bandwidth_rule`` and ``bandwidth_factor`` — ``decay``, ``n_features_in``,
``series`` — the value given: ``True``, ``False`` or ``"auto"`` — and, where set,
``grid`` and ``binned``), then the accumulator's
:meth:`~flexarm.ident.regression.accumulators.Accumulator.state`.

Format 2 holds the blocked sums
(:mod:`~flexarm.ident.regression.accumulators.blocks`); format 1 files (before
them) still load: exact and binned modes resume bit for bit; a grid or series
state resumes with its sums as the total of complete blocks (agreeing with an
uninterrupted fit to rounding), and series mode then evaluates by the series
everywhere (format 1 has no band sums).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import InvalidTypeError, InvalidValueError
from .._estimator import Fitted
from .accumulators import Accumulator, State
from .bandwidth import Silverman, as_rule

__all__ = ["FORMAT", "RegressionState", "hyperparameters", "state_arrays"]

FORMAT = 2  # version of the file layout (2: blocked sums; 1 still loads)


@dataclass(frozen=True)
class RegressionState(Fitted):
    """What a fit of a kernel regression estimator leaves (module docstring).

    Attributes
    ----------
    params : dict
        The hyperparameters as the first fit found them.
    accumulator : Accumulator
        The mode's streaming state; ``accumulator.setup`` is the validated
        :class:`~flexarm.ident.regression.accumulators.Smoothing`.
    """

    accumulator: Accumulator


def state_arrays(fitted: RegressionState, owner: str) -> State:
    """The file's arrays: the frozen hyperparameters, then the accumulator's state."""
    acc, given = fitted.accumulator, fitted.params
    setup = acc.setup
    if not isinstance(setup.kernel, str):
        raise InvalidTypeError(
            f"The 'kernel' parameter of {owner} must be a kernel name to save the "
            f"estimator. Got {setup.kernel!r} instead."
        )
    rule = as_rule(given["bandwidth"], owner)
    out: State = {
        "format": np.array(FORMAT),
        "estimator": np.array(owner),
        "kernel": np.array(setup.kernel),
        # the value given, or the rule's value (with the rule's name and factor below)
        "bandwidth": setup.bandwidth
        if rule is not None
        else np.asarray(given["bandwidth"], dtype=np.float64),
        "decay": np.array(setup.decay),
        "n_features_in": np.array(setup.d),
        # the value given (True, False or "auto"); the mode follows from it
        "series": np.array(given["series"]),
    }
    if rule is not None:
        out.update(bandwidth_rule=np.array(rule.name), bandwidth_factor=np.array(rule.factor))
    if setup.grid is not None:
        out["grid"] = setup.grid
    if setup.binned is not None:
        out["binned"] = np.array(setup.binned)
    out.update(acc.state())
    return out


def hyperparameters(
    data: Mapping[str, NDArray[Any]], owner: str, names: list[str]
) -> tuple[dict[str, Any], int, NDArray[np.float64]]:
    """The constructor's arguments, ``d`` and the resolved ``h_1`` of a saved estimator.

    ``owner`` is the class loading the file, ``names`` its parameter names.
    """
    if int(data.get("format", -1)) not in (1, FORMAT) or str(data.get("estimator")) != owner:
        raise InvalidValueError(
            f"The 'path' parameter of {owner}.load must name a file saved by "
            f"{owner}.save. Got {data.get('estimator', 'another file')!s} instead."
        )
    bw = data["bandwidth"]
    kwargs: dict[str, Any] = {
        "kernel": str(data["kernel"]),
        "bandwidth": float(bw) if bw.ndim == 0 else bw,
        "grid": data.get("grid"),
    }
    if "bandwidth_rule" in data:
        factor = float(data["bandwidth_factor"])
        kwargs["bandwidth"] = "silverman" if factor == 1.0 else Silverman(factor)
    if "decay" in names:
        kwargs["decay"] = float(data["decay"])
    if "binned" in data:
        kwargs["binned"] = float(data["binned"])
    series = data.get("series", np.array(False))  # format 1: a bool (its default was False)
    kwargs["series"] = str(series) if series.dtype.kind == "U" else bool(series)
    d = int(data["n_features_in"])
    h1 = np.ascontiguousarray(np.broadcast_to(np.asarray(bw, dtype=np.float64), (d,)))
    return kwargs, d, h1
