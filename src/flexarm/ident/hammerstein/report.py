"""What a Hammerstein identification did and how far to trust it: :class:`IdentificationReport`.

:class:`~flexarm.ident.HammersteinIdentifier` fills one after every
:meth:`~flexarm.ident.HammersteinIdentifier.fit`: the path taken and why (the
input's whiteness, :mod:`flexarm.ident.hammerstein.whiteness`), the structure and how it was
chosen, the free-run fit of the model beside its linear baseline
(:class:`~flexarm.ident.LinearARX`) on the same record, the comparison with the
best linear model on a validation part (:mod:`flexarm.ident.hammerstein.comparison`:
which won, by how much, what to use), and the warnings raised
(:class:`~flexarm.ident.hammerstein.whiteness.IdentificationWarning`). Plain
values only, so that it is saved and loaded with the identifier.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from .comparison import Comparison

__all__ = ["IdentificationReport", "build_report"]


@dataclass(frozen=True)
class IdentificationReport:
    """The path, the structure and the comparison with the linear baseline.

    Attributes
    ----------
    method : {"white", "correlated"}
        The path used.
    requested : {"auto", "white", "correlated"}
        The ``method`` asked for.
    reason : str
        Why that path (the whiteness verdict, or that it was forced).
    whiteness : dict or None
        :meth:`~flexarm.ident.hammerstein.whiteness.WhitenessReport.summary` of the input.
    structure : dict
        White path: lags, ARMA order and criterion. Correlated path: order,
        knots, estimator, and the held-out selection
        (:meth:`~flexarm.ident.hammerstein.correlated.selection.Selection.summary`).
    fit_percent : float
        Free-run fit of the Hammerstein model on the record it was fitted to, %.
    baseline : dict
        The linear baseline (:class:`~flexarm.ident.LinearARX`): ``order``,
        ``estimator``, ``fit_percent`` (free run on the same record, %).
    nonlinear_helps : bool
        The Hammerstein model beat the best linear model on the validation part
        (``comparison.winner == "hammerstein"``; without a comparison, its fit on
        the record exceeds the baseline's).
    warnings : tuple of str
        The warnings raised by the fit (also issued as ``IdentificationWarning``).
    comparison : Comparison or None
        The Hammerstein model beside the best linear model over the orders
        searched, on a validation part (:mod:`flexarm.ident.hammerstein.comparison`):
        which won, by how much, what to use. None if the record was too short for
        it (white path) or for a file saved before it existed.
    """

    method: str
    requested: str
    reason: str
    whiteness: dict[str, Any] | None
    structure: dict[str, Any]
    fit_percent: float
    baseline: dict[str, Any]
    nonlinear_helps: bool
    warnings: tuple[str, ...] = field(default=())
    comparison: Comparison | None = None

    @property
    def winner(self) -> str | None:
        """``"hammerstein"`` or ``"linear"``: which won on the validation part (None
        without a comparison)."""
        return None if self.comparison is None else self.comparison.winner

    @property
    def loses_to_baseline(self) -> bool:
        """Whether the Hammerstein model's fit is below its linear baseline's."""
        return bool(self.fit_percent < self.baseline["fit_percent"])

    def summary(self) -> dict[str, Any]:
        """Plain values for JSON."""
        return {
            "method": self.method,
            "requested": self.requested,
            "reason": self.reason,
            "whiteness": self.whiteness,
            "structure": self.structure,
            "fit_percent": self.fit_percent,
            "baseline": dict(self.baseline),
            "nonlinear_helps": self.nonlinear_helps,
            "loses_to_baseline": self.loses_to_baseline,
            "winner": self.winner,
            "comparison": None if self.comparison is None else self.comparison.summary(),
            "warnings": list(self.warnings),
        }

    @classmethod
    def from_summary(cls, data: dict[str, Any]) -> IdentificationReport:
        """The report back from :meth:`summary` (as saved with the identifier)."""
        return cls(
            data["method"],
            data["requested"],
            data["reason"],
            data["whiteness"],
            data["structure"],
            float(data["fit_percent"]),
            dict(data["baseline"]),
            bool(data["nonlinear_helps"]),
            tuple(data["warnings"]),
            None if data.get("comparison") is None else Comparison.from_summary(data["comparison"]),
        )


def build_report(
    p: Mapping[str, Any],
    path: str,
    reason: str,
    white: Any,
    solution: Any,
    result: Any,
    fit_percent: float,
    baseline: Any,
    baseline_fit_percent: float,
    notes: list[str],
    comparison: Comparison | None = None,
) -> IdentificationReport:
    """The report of one fit (a model that loses to its baseline adds a note, and one that
    the comparison on the validation part finds worse than a linear model recommends it).

    Parameters
    ----------
    p : mapping
        The validated hyperparameters.
    path, reason : str
        The path taken and why.
    white : WhitenessReport
        The input's whiteness.
    solution : Solution
        The identified model.
    result : CorrelatedResult or None
        The correlated path's structure and selection.
    fit_percent, baseline_fit_percent : float
        Free-run fits on the record of the model and of ``baseline`` (a fitted
        :class:`~flexarm.ident.LinearARX`), %.
    notes : list of str
        Warnings so far (appended to).
    comparison : Comparison, optional
        The model beside the best linear model on the validation part.
    """
    if path == "white":
        structure: dict[str, Any] = {
            "n_lags": p["n_lags"],
            "arma_order": solution.arma.order,
            "order_rule": "bic" if p["order"] == "auto" else p["order"],
            "criterion": {str(k): v for k, v in solution.arma.criterion.items()},
        }
        helps = bool(fit_percent > baseline_fit_percent)  # without a comparison
    else:
        structure = {
            "order": result.fit.order,
            "n_knots": result.fit.n_knots,
            "estimator": result.fit.estimator,
            "iv_steps": result.fit.iv_steps,
            "chosen_by": "given" if p["order"] != "auto" and p["n_knots"] else "held-out",
            "selection": result.selection.summary(),
        }
        helps = bool(result.selection.nonlinear_helps)
    if comparison is not None:
        helps = comparison.winner == "hammerstein"
        if comparison.recommended == "baseline":
            notes.append(comparison.statement())
    if fit_percent < baseline_fit_percent - 1e-9 * max(1.0, abs(baseline_fit_percent)):
        notes.append(
            f"the Hammerstein model's free-run fit ({fit_percent:.2f} %) is below its linear "
            f"baseline's ({baseline_fit_percent:.2f} %, ARX order {baseline.order_}) on the "
            "same record"
        )
    return IdentificationReport(
        method=path,
        requested=p["method"],
        reason=reason,
        whiteness=white.summary(),
        structure=structure,
        fit_percent=fit_percent,
        baseline={
            "order": baseline.order_,
            "estimator": baseline.estimator_,
            "fit_percent": baseline_fit_percent,
        },
        nonlinear_helps=helps,
        warnings=tuple(notes),
        comparison=comparison,
    )
