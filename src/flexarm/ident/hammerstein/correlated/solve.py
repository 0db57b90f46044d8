r"""The correlated-input path of :class:`~flexarm.ident.HammersteinIdentifier`.

For an input that is not white (a sweep, a multisine, coloured noise,
closed-loop data) the correlation approach's lag regressions mix the
impulse response with the input's autocorrelation. This path instead fits
the ARX-Hammerstein structure directly (:mod:`flexarm.ident.hammerstein.correlated.arx`: over-
parameterised least squares on a piecewise-linear basis for ``phi``,
Bai's rank-one separation, instrumental-variable refinement), which needs
only a persistently exciting input. Its order and knots come from held-out
data (:mod:`flexarm.ident.hammerstein.correlated.selection`), and so does the linear baseline
(:class:`~flexarm.ident.LinearARX`) it is reported beside.

:func:`solve_correlated` returns the same
:class:`~flexarm.ident.hammerstein.solution.Solution` as the white-input path
(grid = the knots, the impulse response of the fitted ARMA model, the singular
values of the separated array), normalised the same way: by the two known
points if given, otherwise with the impulse response's entry of largest
magnitude ``+1`` and ``phi`` of mean zero over the inputs — which fixes the sign
shared by ``phi`` and the impulse response.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...._types import F64
from ....errors import InvalidValueError
from ..solution import ARMAFit, KnownPoints, Solution, two_point_normalisation
from ..systems import ARMA
from .arx import StructureFit
from .hatbasis import evaluate, locate
from .selection import Selection, final_fit, select_structure

__all__ = ["CorrelatedResult", "solve_correlated"]


@dataclass(frozen=True)
class CorrelatedResult:
    """The correlated path's outcome.

    Attributes
    ----------
    solution : Solution
        The identified model in the white path's terms (module docstring).
    fit : StructureFit
        The chosen structure refitted to the whole record (before normalisation).
    selection : Selection
        The structures tried on held-out data, the choice and the linear baseline's.
    """

    solution: Solution
    fit: StructureFit
    selection: Selection


def _input_weights(u: F64, knots: F64) -> F64:
    """Share of the inputs carried by each knot's hat function, shape (K,), sum 1."""
    seg, pos = locate(u, np.asarray(knots))
    w = np.clip(pos, 0.0, 1.0)
    k = knots.shape[0]
    mass = np.bincount(seg, weights=1.0 - w, minlength=k) + np.bincount(
        seg + 1, weights=w, minlength=k
    )
    out: F64 = mass / np.sum(mass)
    return out


def normalise(
    fit: StructureFit,
    u: F64,
    y: F64,
    *,
    n_lags: int,
    known_points: KnownPoints | None,
    criterion: dict[int, float],
    owner: str,
) -> Solution:
    """``fit`` as a :class:`Solution`, normalised by two points or the largest entry."""
    shape = fit.phi
    base = ARMA(tuple(fit.a.tolist()), tuple(fit.b.tolist()))
    lags = base.impulse_response(n_lags)
    if known_points is None:
        scale = float(lags[int(np.argmax(np.abs(lags)))])
        phi, b = shape * scale, fit.b / scale
    else:
        (x1, f1), (x2, f2) = known_points
        lo, hi = float(fit.knots[0]), float(fit.knots[-1])
        for x in (x1, x2):
            if not lo <= x <= hi:
                raise InvalidValueError(
                    f"The 'known_points' parameter of {owner} must lie within the input's "
                    f"range [{lo:.6g}, {hi:.6g}]. Got x = {x} instead."
                )
        s1, s2 = evaluate(*locate(np.array([x1, x2]), fit.knots), shape)
        if s1 == s2:
            raise InvalidValueError(
                f"The 'known_points' parameter of {owner} must name points where the "
                f"estimate differs. Got equal estimates at x1 = {x1} and x2 = {x2} instead."
            )
        d1, alpha = two_point_normalisation(float(s1), float(s2), f1, f2)
        phi, b = (shape - alpha) / d1, fit.b * d1
    model = ARMA(tuple(fit.a.tolist()), tuple(b.tolist()))
    offset = fit.offset
    if known_points is not None:  # phi moved: the offset that fits the free run best again
        offset = float(np.mean(y - model.filter(evaluate(*locate(u, fit.knots), phi))))
    return Solution(
        lags=lags,
        shape=shape.copy(),
        grid=fit.knots.copy(),
        weights=_input_weights(u, fit.knots),
        impulse=model.impulse_response(n_lags),
        nonlinearity=phi,
        arma=ARMAFit(model, fit.order, dict(criterion), {}),
        offset=offset,
        singular_values=fit.singular_values.copy(),
    )


def solve_correlated(
    u: F64,
    y: F64,
    *,
    n_lags: int,
    order: int | None,
    max_order: int,
    n_knots: int | None,
    known_points: KnownPoints | None,
    validation_fraction: float,
    owner: str,
) -> CorrelatedResult:
    """Choose the structure on held-out data, refit it to the record, normalise.

    Parameters
    ----------
    u, y : ndarray, shape (n,)
        The record (checked: finite, varying, ``n >= 100``).
    n_lags : int
        Length of the reported impulse response.
    order, n_knots : int or None
        Fixed order ``l`` and knot count ``K``, or None to choose them.
    max_order : int
        Largest order tried.
    known_points : ((x1, phi1), (x2, phi2)) or None
        Two-point normalisation.
    validation_fraction : float
        Trailing fraction held out for the choice.
    owner : str
        Named in error messages.
    """
    sel = select_structure(
        u,
        y,
        max_order=max_order,
        order=order,
        n_knots=n_knots,
        validation_fraction=validation_fraction,
    )
    if sel is None:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must be explained by a stable model of some order. "
            "Got no stable fit on the estimation part instead (is the input exciting?)."
        )
    fit = final_fit(u, y, sel.chosen)
    criterion = {
        c.order: c.validation_mse for c in sel.candidates if c.n_knots == sel.chosen.n_knots
    }
    sol = normalise(
        fit, u, y, n_lags=n_lags, known_points=known_points, criterion=criterion, owner=owner
    )
    return CorrelatedResult(sol, fit, sel)
