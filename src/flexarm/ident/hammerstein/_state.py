"""The fitted state of :class:`~flexarm.ident.HammersteinIdentifier`, and its plain arrays.

:class:`HammersteinState` is what a fit leaves: the hyperparameters it froze and
their checked values, the path, the white path's streaming state (the lag
regressions) or the correlated path's result, the identified model, and after a
:meth:`~flexarm.ident.HammersteinIdentifier.fit` the input's whiteness, the linear
baseline and the report.

As plain arrays (``to_arrays``, the ``.npz`` file of ``save``, no pickle; format
2): ``format``, ``estimator``, ``params`` (the hyperparameters as JSON), ``path``
(``"white"`` or ``"correlated"``), and, after a ``fit``, ``report``,
``whiteness`` and ``baseline`` (JSON). The white path adds its streaming state
(the lag regressions' arrays, :mod:`flexarm.ident.regression.accumulators`) so
that streaming resumes bit for bit; the correlated path adds its fitted model
(``grid``, ``nonlinearity``, ``a``, ``b``, ...). Files of format 1 (the white
path before the correlated one existed) load as white-path identifiers.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ...errors import InvalidValueError
from .._estimator import Fitted
from ..regression.accumulators import State
from ..regression.bandwidth import Silverman
from ._params import validate
from .correlated.solve import CorrelatedResult
from .linear import LinearARX, LinearFit, LinearModel
from .report import IdentificationReport
from .solution import ARMAFit, Solution
from .systems import ARMA
from .white.lags import LagRegressions
from .whiteness import WhitenessReport

__all__ = ["FORMAT", "HammersteinState", "state_arrays", "state_from_arrays"]

FORMAT = 2  # version of the file layout
_OWNER = "HammersteinIdentifier"
_SOLUTION = ("lags", "shape", "grid", "weights", "impulse", "nonlinearity", "singular_values")


@dataclass(frozen=True)
class HammersteinState(Fitted):
    """What a fit of :class:`~flexarm.ident.HammersteinIdentifier` leaves (module docstring).

    Attributes
    ----------
    params : dict
        The hyperparameters as the first fit found them.
    checked : dict
        Their checked values (as the first fit checked them).
    path : {"white", "correlated"}
        The path taken.
    lags : LagRegressions or None
        White path: the streaming state.
    solution : Solution or None
        The identified model (white path: computed from ``lags`` when first
        needed, until the next chunk).
    n_samples : int
        Correlated path: samples of the record (the white path counts in ``lags``).
    result : CorrelatedResult or None
        Correlated path, fitted in this session: the structure and its selection.
    whiteness : WhitenessReport or None
        After ``fit``: the input's whiteness.
    baseline : LinearARX or None
        After ``fit``: the linear baseline fitted to the same record.
    report : IdentificationReport or None
        After ``fit``: what it did.
    """

    checked: dict[str, Any]
    path: str
    lags: LagRegressions | None = None
    solution: Solution | None = None
    n_samples: int = 0
    result: CorrelatedResult | None = None
    whiteness: WhitenessReport | None = None
    baseline: LinearARX | None = None
    report: IdentificationReport | None = None


def _plain(value: Any) -> Any:
    """NumPy scalars and arrays as plain Python values, for JSON."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _json(value: Any) -> NDArray[Any]:
    return np.array(json.dumps(value, default=_plain))


def _baseline_json(base: LinearARX) -> dict[str, Any]:
    fit = base.state_
    m = fit.model
    return {
        "params": fit.params,
        "n_samples": fit.n_samples,
        "n_lags": fit.n_lags,
        "a": list(m.arma.a),
        "b": list(m.arma.b),
        "offset": m.offset,
        "input_mean": m.input_mean,
        "order": m.order,
        "estimator": m.estimator,
    }


def _baseline_from(data: Mapping[str, Any]) -> LinearARX:
    arma = ARMA(tuple(data["a"]), tuple(data["b"]))
    model = LinearModel(arma, data["offset"], data["input_mean"], data["order"], data["estimator"])
    fit = LinearFit(dict(data["params"]), model, None, int(data["n_samples"]), int(data["n_lags"]))
    return LinearARX.from_state(fit)


def state_arrays(state: HammersteinState) -> State:
    """Everything :func:`state_from_arrays` needs, as plain arrays."""
    params = dict(state.params)
    if isinstance(params["bandwidth"], Silverman):
        params["bandwidth"] = {"silverman": params["bandwidth"].factor}
    out: State = {
        "format": np.array(FORMAT),
        "estimator": np.array(_OWNER),
        "params": _json(params),
        "path": np.array(state.path),
    }
    if state.report is not None:
        assert state.whiteness is not None and state.baseline is not None
        out["report"] = _json(state.report.summary())
        out["whiteness"] = _json(asdict(state.whiteness))
        out["baseline"] = _json(_baseline_json(state.baseline))
    if state.path == "white":
        assert state.lags is not None
        return {**out, **state.lags.state()}
    sol = state.solution
    assert sol is not None  # the correlated path's model is its state
    for name in _SOLUTION:
        out[name] = np.asarray(getattr(sol, name))
    model = sol.arma.model
    out.update(
        a=np.asarray(model.a, dtype=np.float64),
        b=np.asarray(model.b, dtype=np.float64),
        arma_order=np.array(sol.arma.order),
        criterion=_json({str(k): v for k, v in sol.arma.criterion.items()}),
        offset=np.array(sol.offset),
        n_samples=np.array(state.n_samples),
    )
    return out


def state_from_arrays(data: Mapping[str, NDArray[Any]]) -> HammersteinState:
    """The state :func:`state_arrays` described (formats 1 and 2)."""
    fmt = int(data.get("format", -1))
    if fmt not in (1, FORMAT) or str(data.get("estimator")) != _OWNER:
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
    checked = validate(params)
    path = str(data["path"]) if "path" in data else "white"
    fitted: dict[str, Any] = {}
    if "report" in data:
        white = json.loads(str(data["whiteness"]))
        white["autocorrelation"] = np.asarray(white["autocorrelation"], dtype=np.float64)
        fitted.update(
            report=IdentificationReport.from_summary(json.loads(str(data["report"]))),
            whiteness=WhitenessReport(**white),
            baseline=_baseline_from(json.loads(str(data["baseline"]))),
        )
    if path == "white":
        lags = LagRegressions.from_state(checked, _OWNER, data)
        return HammersteinState(params, checked, path, lags=lags, **fitted)
    criterion = {int(k): float(v) for k, v in json.loads(str(data["criterion"])).items()}
    model = ARMA(tuple(data["a"].tolist()), tuple(data["b"].tolist()))
    arrays = {name: np.array(data[name], dtype=np.float64) for name in _SOLUTION}
    solution = Solution(
        **arrays,
        arma=ARMAFit(model, int(data["arma_order"]), criterion, {}),
        offset=float(data["offset"]),
    )
    n = int(data["n_samples"])
    return HammersteinState(params, checked, path, solution=solution, n_samples=n, **fitted)
