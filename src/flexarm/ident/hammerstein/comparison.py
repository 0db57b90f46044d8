r"""Whether the Hammerstein model beats the best linear model: :class:`Comparison`.

A nonlinear model is worth its parameters only if it predicts data it was not
fitted to better than every linear model would. Every
:meth:`~flexarm.ident.HammersteinIdentifier.fit` therefore compares, on a
validation part of the record, the free run of the Hammerstein model against
the **best** linear ARX model over every order ``1 .. max_order`` (the smallest
validation error; each fitted by :mod:`flexarm.ident.hammerstein.correlated.arx`
with two knots), both estimated without the validation part:

* correlated-input path: the held-out blocks of the structure's selection
  (:mod:`flexarm.ident.hammerstein.correlated.selection`: every ``p``-th of ``5 p``
  contiguous blocks, ``p = round(1 / validation_fraction)``); the nonlinear side
  is the chosen structure, or, when a linear one was chosen, the best nonlinear
  structure tried;
* white-input path: the trailing ``validation_fraction`` of the record, the
  paper's estimate taken from the streaming state after the leading part
  (the final model continues from it over the whole record, bit for bit as one
  fit).

The Hammerstein model **wins** if its validation mean square error is below the
best linear one's by more than the standard error of the difference
(:func:`~flexarm.ident.hammerstein.correlated.selection.standard_error`: batch
means of the squared-error differences, plus the spread of the two fits'
estimation excess); otherwise the linear model wins. The comparison says which
won, by how much (mean square error, fit in percent, standard errors) and what
to use: the identifier itself, or its linear baseline
(:attr:`~flexarm.ident.HammersteinIdentifier.baseline_`), which the identifier
then recommends by a warning. :meth:`~flexarm.ident.HammersteinIdentifier.compare`
makes the same comparison of the identifier and its baseline on data given.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..._types import F64
from .correlated.selection import (
    Candidate,
    Selection,
    batch_errors,
    linear_candidates,
    standard_error,
    trailing,
    validation_fit,
)
from .prediction import predict_output
from .solution import Solution

__all__ = ["WINNERS", "Comparison", "compare_outputs", "correlated_comparison", "white_comparison"]


#: The two possible winners.
WINNERS = ("hammerstein", "linear")


@dataclass(frozen=True)
class Comparison:
    """The Hammerstein model beside the best linear model on a validation part (module doc).

    Attributes
    ----------
    part : str
        Which samples validated, in words.
    n_validation : int
        Samples of the validation part.
    model : str
        The Hammerstein model compared (its structure, in words).
    model_mse, linear_mse : float
        Free-run mean square errors on the validation part (units of ``y`` squared)
        of the Hammerstein model and of the best linear model.
    model_fit_percent, linear_fit_percent : float
        The same as fits, ``100 (1 - ||e|| / ||y - mean y||)`` on the part, %.
    linear_order : int
        Order of the best linear model.
    orders : tuple of int
        The linear orders compared (those with a stable fit).
    standard_error : float
        Of ``linear_mse - model_mse`` (units of ``y`` squared).
    winner : {"hammerstein", "linear"}
        The Hammerstein model wins if it is better by more than ``standard_error``.
    recommended : {"identifier", "baseline"}
        What to use: the identifier's own model (the winner, or already the linear
        model), or its linear baseline.
    baseline_order : int
        Order of the identifier's linear baseline (chosen by the one-standard-error
        rule: within a standard error of the best linear model, with fewer parameters).
    """

    part: str
    n_validation: int
    model: str
    model_mse: float
    model_fit_percent: float
    linear_order: int
    linear_mse: float
    linear_fit_percent: float
    orders: tuple[int, ...]
    standard_error: float
    winner: str
    recommended: str
    baseline_order: int

    @property
    def margin(self) -> float:
        """``linear_mse - model_mse``: positive where the Hammerstein model is better."""
        return self.linear_mse - self.model_mse

    @property
    def relative(self) -> float:
        """``margin / linear_mse``: the share of the best linear model's error removed."""
        return self.margin / self.linear_mse if self.linear_mse > 0.0 else 0.0

    def statement(self) -> str:
        """Which won and by how much, in one sentence."""
        sign = "lower" if self.margin >= 0.0 else "higher"
        se = abs(self.margin) / self.standard_error if self.standard_error > 0.0 else math.inf
        verb = "beats" if self.winner == "hammerstein" else "does not beat"
        against = f"ARX({self.linear_order})"
        if len(self.orders) > 1:
            against = f"{against}, over orders {_orders(self.orders)}"
        if self.recommended == "baseline":
            use = f"use the linear baseline ARX({self.baseline_order}) (baseline_, recommended_)"
        elif self.winner == "linear":
            use = f"the identifier's model is the linear ARX({self.baseline_order}) of its baseline"
        else:
            use = "the identifier's model is the one to use"
        need = "" if self.winner == "hammerstein" else "; a win needs more than one"
        return (
            f"the Hammerstein model ({self.model}) {verb} the best linear model ({against}) "
            f"on the {self.part} ({self.n_validation} samples): free-run fit "
            f"{self.model_fit_percent:.2f} % against {self.linear_fit_percent:.2f} %, mean "
            f"square error {abs(self.relative):.1%} {sign} ({se:.1f} standard errors{need}); "
            f"{use}"
        )

    def summary(self) -> dict[str, Any]:
        """Plain values for JSON (the statement included)."""
        out: dict[str, Any] = {
            "part": self.part,
            "n_validation": self.n_validation,
            "model": self.model,
            "model_mse": self.model_mse,
            "model_fit_percent": self.model_fit_percent,
            "linear_order": self.linear_order,
            "linear_mse": self.linear_mse,
            "linear_fit_percent": self.linear_fit_percent,
            "orders": list(self.orders),
            "standard_error": self.standard_error,
            "winner": self.winner,
            "recommended": self.recommended,
            "baseline_order": self.baseline_order,
            "margin": self.margin,
            "relative": self.relative,
            "statement": self.statement(),
        }
        return {
            k: (v if not isinstance(v, float) or math.isfinite(v) else None) for k, v in out.items()
        }

    @classmethod
    def from_summary(cls, data: dict[str, Any]) -> Comparison:
        """The comparison back from :meth:`summary`."""

        def real(key: str) -> float:
            v = data[key]
            return -math.inf if v is None else float(v)

        return cls(
            str(data["part"]),
            int(data["n_validation"]),
            str(data["model"]),
            real("model_mse"),
            real("model_fit_percent"),
            int(data["linear_order"]),
            real("linear_mse"),
            real("linear_fit_percent"),
            tuple(int(o) for o in data["orders"]),
            real("standard_error"),
            str(data["winner"]),
            str(data["recommended"]),
            int(data["baseline_order"]),
        )


def _orders(orders: tuple[int, ...]) -> str:
    if not orders:
        return "(none)"
    if list(orders) == list(range(orders[0], orders[-1] + 1)) and len(orders) > 2:
        return f"{orders[0]}-{orders[-1]}"
    return ", ".join(str(o) for o in orders)


def _structure(c: Candidate) -> str:
    return f"order {c.order}, {c.n_knots} knots" if not c.linear else f"order {c.order}, linear"


def _decide(model: Candidate, linear: Candidate, rows: float) -> tuple[str, float]:
    se = standard_error(model, linear, rows)
    won = linear.validation_mse - model.validation_mse > se
    return ("hammerstein" if won else "linear"), se


def correlated_comparison(sel: Selection) -> Comparison:
    """The comparison on the held-out blocks of the correlated path's ``sel``."""
    nonlinear = [c for c in sel.candidates if not c.linear and math.isfinite(c.validation_mse)]
    if sel.chosen.linear and nonlinear:  # the strongest nonlinear structure that lost
        model = min(nonlinear, key=lambda c: (c.validation_mse, c.n_params))
    else:
        model = sel.chosen
    lin = sel.best_linear
    _, se = _decide(model, lin, sel.rows)
    winner = sel.winner
    returns_linear = sel.chosen.linear and sel.chosen is sel.linear
    recommended = "identifier" if winner == "hammerstein" or returns_linear else "baseline"
    orders = tuple(
        sorted({c.order for c in sel.candidates if c.linear and math.isfinite(c.validation_mse)})
    )
    return Comparison(
        part=sel.part,
        n_validation=sel.n_validation,
        model=_structure(model),
        model_mse=model.validation_mse,
        model_fit_percent=sel.fit_percent(model),
        linear_order=lin.order,
        linear_mse=lin.validation_mse,
        linear_fit_percent=sel.fit_percent(lin),
        orders=orders,
        standard_error=se,
        winner=winner,
        recommended=recommended,
        baseline_order=sel.linear.order,
    )


def white_comparison(
    u: F64, y: F64, sol: Solution, n_estimation: int, *, max_order: int, baseline_order: int
) -> Comparison | None:
    """The comparison on the trailing part ``n_estimation ..`` of the record (white path).

    ``sol`` is the white path's model estimated on the leading part (its free run
    over the whole record is scored; it carries its grid values and ARMA
    coefficients, the estimation excess of the standard error). None if no
    linear model is stable.
    """
    split = trailing(u.shape[0], n_estimation)
    linear, rows = linear_candidates(u, y, max_order, split)
    if not linear:
        return None
    _, held, index = split
    model_arma = sol.arma.model
    phi = np.interp(u[index], sol.grid, sol.nonlinearity)  # from rest where the window starts
    y_model = predict_output(model_arma, phi, sol.offset, None, None, owner="white_comparison")
    n_params = sol.grid.shape[0] + len(model_arma.a) + len(model_arma.b)
    label = f"white path, ARMA order {sol.arma.order}, {sol.grid.shape[0]} grid points"
    y = y[index]
    err = (y[held] - y_model[held]) ** 2
    batches = batch_errors(err)
    mse = float(np.mean(batches))
    model = Candidate(0, 0, n_params, mse, "white path", batches, None)
    lin = min(linear, key=lambda c: (c.validation_mse, c.n_params))
    winner, se = _decide(model, lin, rows)
    variance = float(np.var(y[held]))
    return Comparison(
        part=_trailing_part(n_estimation, int(index[-1]), int(index[split[0].mask][0])),
        n_validation=int(np.count_nonzero(held)),
        model=label,
        model_mse=mse,
        model_fit_percent=validation_fit(mse, variance),
        linear_order=lin.order,
        linear_mse=lin.validation_mse,
        linear_fit_percent=validation_fit(lin.validation_mse, variance),
        orders=tuple(sorted(c.order for c in linear)),
        standard_error=se,
        winner=winner,
        recommended="identifier" if winner == "hammerstein" else "baseline",
        baseline_order=baseline_order,
    )


def _trailing_part(n_estimation: int, last: int, linear_start: int) -> str:
    """The white path's validation part, in words."""
    if linear_start == 0:
        fitted = f"the models estimated on samples 0 to {n_estimation - 1}"
    else:
        fitted = (
            f"the linear models estimated on samples {linear_start} to {n_estimation - 1}, the "
            f"Hammerstein model on samples 0 to {n_estimation - 1}"
        )
    return f"trailing part of the record (samples {n_estimation} to {last}; {fitted})"


def compare_outputs(
    y: F64, y_model: F64, y_linear: F64, *, model: str, order: int, skip: int = 0
) -> Comparison:
    """The comparison of two fixed models' outputs on data ``y`` (samples ``skip ..``
    validate). The standard error is the batch-means one alone (neither model is
    fitted here)."""
    y, y_model, y_linear = y[skip:], y_model[skip:], y_linear[skip:]
    e_model, e_linear = (y - y_model) ** 2, (y - y_linear) ** 2
    b_model, b_linear = batch_errors(e_model), batch_errors(e_linear)
    d = b_linear - b_model
    se = float(np.std(d, ddof=1) / math.sqrt(d.shape[0])) if d.shape[0] > 1 else 0.0
    m_model, m_linear = float(np.mean(b_model)), float(np.mean(b_linear))
    variance = float(np.var(y))
    winner = "hammerstein" if m_linear - m_model > se else "linear"
    return Comparison(
        part="data given" if skip == 0 else f"data given from sample {skip} on",
        n_validation=int(y.shape[0]),
        model=model,
        model_mse=m_model,
        model_fit_percent=validation_fit(m_model, variance),
        linear_order=order,
        linear_mse=m_linear,
        linear_fit_percent=validation_fit(m_linear, variance),
        orders=(order,),
        standard_error=se,
        winner=winner,
        recommended="identifier" if winner == "hammerstein" else "baseline",
        baseline_order=order,
    )
