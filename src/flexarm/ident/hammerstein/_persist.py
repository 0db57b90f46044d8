"""Saving and loading :class:`~flexarm.ident.HammersteinIdentifier` (NumPy ``.npz``, no pickle).

Layout (format 2): ``format``, ``estimator``, ``params`` (the hyperparameters
as JSON), ``path`` (``"white"`` or ``"correlated"``), and, after a
:meth:`~flexarm.ident.HammersteinIdentifier.fit`, ``report``, ``whiteness``
and ``baseline`` (JSON). The white path adds its streaming state (the lag
regressions' state description, :mod:`flexarm.ident.regression.accumulators`) so that
streaming resumes bit for bit; the correlated path adds its fitted model
(``grid``, ``nonlinearity``, ``a``, ``b``, ...). Files of format 1 (the white
path before the correlated one existed) load as white-path identifiers.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from dataclasses import asdict
from typing import Any, TypeVar

import numpy as np
from numpy.typing import NDArray

from ..._io import atomic_path
from ...errors import InvalidValueError
from .._estimator import NotFittedError
from ..regression.accumulators import State
from ..regression.bandwidth import Silverman
from .linear import LinearARX, LinearModel
from .report import IdentificationReport
from .solution import ARMAFit, Solution
from .systems import ARMA
from .white.lags import LagRegressions
from .whiteness import WhitenessReport

__all__ = ["FORMAT", "load", "save"]

FORMAT = 2  # version of the file layout
_OWNER = "HammersteinIdentifier"
_SOLUTION = ("lags", "shape", "grid", "weights", "impulse", "nonlinearity", "singular_values")
_H = TypeVar("_H")


def _plain(value: Any) -> Any:
    """NumPy scalars and arrays as plain Python values, for JSON."""
    if isinstance(value, np.ndarray | np.generic):
        return value.tolist()
    raise TypeError(f"{type(value).__name__} is not JSON serialisable")


def _json(value: Any) -> NDArray[Any]:
    return np.array(json.dumps(value, default=_plain))


def _baseline_json(base: LinearARX) -> dict[str, Any]:
    m = base.model_
    return {
        "params": base.get_params(),
        "n_samples": base.n_samples_,
        "n_lags": base._n_lags,
        "a": list(m.arma.a),
        "b": list(m.arma.b),
        "offset": m.offset,
        "input_mean": m.input_mean,
        "order": m.order,
        "estimator": m.estimator,
    }


def _baseline_from(data: Mapping[str, Any]) -> LinearARX:
    base = LinearARX(**data["params"])
    arma = ARMA(tuple(data["a"]), tuple(data["b"]))
    base.model_ = LinearModel(
        arma, data["offset"], data["input_mean"], data["order"], data["estimator"]
    )
    base.selection_ = None  # type: ignore[assignment]
    base.n_samples_ = int(data["n_samples"])
    base._n_lags = int(data["n_lags"])
    return base


def state(est: Any) -> State:
    """Everything :func:`load` needs, as plain arrays."""
    path = est.__dict__.get("_path")
    if path is None:
        raise NotFittedError(
            f"This {_OWNER} instance is not fitted yet. Call 'fit' or 'partial_fit' "
            "before saving it."
        )
    params = dict(est._frozen)
    if isinstance(params["bandwidth"], Silverman):
        params["bandwidth"] = {"silverman": params["bandwidth"].factor}
    out: State = {
        "format": np.array(FORMAT),
        "estimator": np.array(_OWNER),
        "params": _json(params),
        "path": np.array(path),
    }
    report: IdentificationReport | None = est.__dict__.get("_report")
    if report is not None:
        out["report"] = _json(report.summary())
        out["whiteness"] = _json(asdict(est.whiteness_))
        out["baseline"] = _json(_baseline_json(est.baseline_))
    if path == "white":
        return {**out, **est._lags.state()}
    sol: Solution = est._solution()
    for name in _SOLUTION:
        out[name] = np.asarray(getattr(sol, name))
    model = sol.arma.model
    out.update(
        a=np.asarray(model.a, dtype=np.float64),
        b=np.asarray(model.b, dtype=np.float64),
        arma_order=np.array(sol.arma.order),
        criterion=_json({str(k): v for k, v in sol.arma.criterion.items()}),
        offset=np.array(sol.offset),
        n_samples=np.array(est.n_samples_),
    )
    return out


def save(est: Any, path: str | os.PathLike[str]) -> None:
    """Write :func:`state` to ``path`` atomically (``.npz``, as given)."""
    arrays: dict[str, Any] = state(est)
    with atomic_path(path) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)


def from_state(cls: type[_H], data: Mapping[str, NDArray[Any]]) -> _H:
    """The identifier described by :func:`state` output (formats 1 and 2)."""
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
    est: Any = cls(**params)
    est._params = est._validated()
    est._frozen = est.get_params()
    path = str(data["path"]) if "path" in data else "white"
    est._path = path
    if "report" in data:
        est._report = IdentificationReport.from_summary(json.loads(str(data["report"])))
        white = json.loads(str(data["whiteness"]))
        white["autocorrelation"] = np.asarray(white["autocorrelation"], dtype=np.float64)
        est.whiteness_ = WhitenessReport(**white)
        est.baseline_ = _baseline_from(json.loads(str(data["baseline"])))
    if path == "white":
        est._lags = LagRegressions.from_state(est._params, _OWNER, data)
        white_est: _H = est
        return white_est
    criterion = {int(k): float(v) for k, v in json.loads(str(data["criterion"])).items()}
    model = ARMA(tuple(data["a"].tolist()), tuple(data["b"].tolist()))
    arrays = {name: np.array(data[name], dtype=np.float64) for name in _SOLUTION}
    est._cache = Solution(
        **arrays,
        arma=ARMAFit(model, int(data["arma_order"]), criterion, {}),
        offset=float(data["offset"]),
    )
    est._n_seen = int(data["n_samples"])
    out: _H = est
    return out


def load(cls: type[_H], path: str | os.PathLike[str]) -> _H:
    """Read an identifier written by :func:`save`."""
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    return from_state(cls, data)
