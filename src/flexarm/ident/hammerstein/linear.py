r"""The linear baseline: an ARX model whose order is chosen on held-out data.

``y_n - ybar = a_1 (y_{n-1} - ybar) + ... + a_l (y_{n-l} - ybar)
+ b_0 (u_n - ubar) + ... + b_l (u_{n-l} - ubar)`` — the paper's ARMA(l, l)
convention from the input to the output. :class:`LinearARX` fits it by the
machinery of the correlated-input Hammerstein path with two knots (a linear
``phi``): least squares, instrumental-variable steps kept when they lower the
free-run error (:mod:`flexarm.ident.hammerstein.correlated.arx`), the order by the
one-standard-error rule on the free-run error of the held-out tail
(:mod:`flexarm.ident.hammerstein.correlated.selection`), then the chosen order refitted to the
whole record. Every :class:`~flexarm.ident.HammersteinIdentifier` fit is
reported beside this baseline of the same data, and compared on a validation
part with the best linear model over the orders searched
(:mod:`flexarm.ident.hammerstein.comparison`): a nonlinear model that does not
beat it has found no nonlinearity worth its parameters.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Self

from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import check_int, check_option, check_real
from ...errors import InvalidValueError
from .._estimator import Estimator, Fitted
from .correlated.arx import StructureFit
from .correlated.selection import Selection, final_fit, select_structure
from .prediction import Scored, check_input, check_record, predict_output
from .systems import ARMA

__all__ = ["MIN_SAMPLES", "LinearARX", "LinearFit", "LinearModel", "baseline_fit", "linear_model"]

_OWNER = "LinearARX"

#: Fewest samples of a record identified with held-out validation.
MIN_SAMPLES = 100


@dataclass(frozen=True)
class LinearModel:
    """``y = offset + B/A (u - input_mean)``: a fitted linear model.

    Attributes
    ----------
    arma : ARMA
        From ``u - input_mean`` to ``y - offset``.
    offset : float
        Output offset (units of ``y``): the constant that fits the free run best.
    input_mean : float
        Input level of zero response (units of ``u``): about the data's mean.
    order : int
        ``l``.
    estimator : str
        ``"least squares"`` or ``"instrumental variables"``.
    """

    arma: ARMA
    offset: float
    input_mean: float
    order: int
    estimator: str

    def simulate(self, u: F64) -> F64:
        """Free-run output from rest for the inputs ``u``, shape (n,)."""
        return self.arma.filter(u - self.input_mean) + self.offset


def linear_model(fit: StructureFit) -> LinearModel:
    """The two-knot structure ``fit`` as a linear model of ``u`` (the same free run)."""
    t0, t1 = float(fit.knots[0]), float(fit.knots[1])
    slope = float(fit.phi[1] - fit.phi[0]) / (t1 - t0)
    # phi(u) = phi0 + slope (u - t0) = slope (u - centre): the same free run
    arma = ARMA(tuple(fit.a.tolist()), tuple((slope * fit.b).tolist()))
    centre = t0 - float(fit.phi[0]) / slope
    return LinearModel(arma, fit.offset, centre, fit.order, fit.estimator)


@dataclass(frozen=True)
class LinearFit(Fitted):
    """What a fit of :class:`LinearARX` leaves.

    Attributes
    ----------
    params : dict
        The hyperparameters as the fit found them.
    model : LinearModel
        The fitted model.
    selection : Selection or None
        The orders tried and their held-out errors (None for a baseline loaded
        with its identifier).
    n_samples : int
        Samples of the record.
    n_lags : int
        Length of the impulse response reported.
    """

    model: LinearModel
    selection: Selection | None
    n_samples: int
    n_lags: int


def baseline_fit(
    u: F64, y: F64, selection: Selection, n_lags: int, params: dict[str, Any]
) -> LinearFit:
    """The linear choice of a held-out ``selection`` on the record ``(u, y)``, refitted
    to the whole record: the state of a :class:`LinearARX` with hyperparameters ``params``.

    :meth:`LinearARX.fit` makes the selection itself; the Hammerstein identifier's
    correlated path passes the one it made (its linear candidates are the baseline's).
    """
    model = linear_model(final_fit(u, y, selection.linear))
    return LinearFit(params, model, selection, int(u.shape[0]), n_lags)


class LinearARX(Scored, Estimator[LinearFit]):
    """Linear ARX(l, l) model of ``u -> y``, order by held-out free-run error (module docstring).

    Parameters
    ----------
    order : int or "auto", default "auto"
        ``l >= 1``, or chosen by the one-standard-error rule on held-out data.
    max_order : int, default 10
        Largest order tried by "auto".
    validation_fraction : float, default 0.25
        Trailing fraction of the record held out to choose the order, in (0, 0.5].
    n_lags : int, default 40
        Length of :attr:`impulse_response_`.

    Attributes
    ----------
    n_samples_ : int
        Samples of the record.
    order_ : int
        ``l`` in use.
    arma_ : ARMA
        From ``u - input_mean_`` to ``y - offset_``.
    offset_, input_mean_ : float
        Output offset and input level (units of ``y`` and ``u``):
        ``y_hat = offset_ + B/A (u - input_mean_)``.
    impulse_response_ : ndarray, shape (n_lags,)
        ``arma_``'s impulse response (units of ``y`` per unit of ``u``).
    estimator_ : str
        ``"least squares"`` or ``"instrumental variables"``.
    selection_ : Selection
        The orders tried and their held-out errors.
    state_ : LinearFit
        The fitted state.

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> u = rng.normal(size=3000)
    >>> y = ARMA((0.7,), (1.0, 0.5)).filter(u) + 0.05 * rng.normal(size=3000)
    >>> model = LinearARX().fit(u, y)
    >>> model.order_, np.round(model.arma_.a, 2), np.round(model.arma_.b, 2)
    (1, array([0.7]), array([1. , 0.5]))
    """

    _not_fitted_hint = "Call 'fit' before using it."

    def __init__(
        self,
        order: int | str = "auto",
        max_order: int = 10,
        validation_fraction: float = 0.25,
        n_lags: int = 40,
    ) -> None:
        self.order = order
        self.max_order = max_order
        self.validation_fraction = validation_fraction
        self.n_lags = n_lags

    def _validated(self) -> dict[str, Any]:
        p: dict[str, Any] = {}
        if isinstance(self.order, str):
            check_option(self.order, "order", _OWNER, ("auto",))
            p["order"] = None
        else:
            p["order"] = check_int(self.order, "order", _OWNER, minimum=1)
        p["max_order"] = check_int(self.max_order, "max_order", _OWNER, minimum=1)
        p["validation_fraction"] = check_fraction(self.validation_fraction, _OWNER)
        p["n_lags"] = check_int(self.n_lags, "n_lags", _OWNER, minimum=1)
        return p

    def fit(self, u: ArrayLike, y: ArrayLike) -> Self:
        """Choose the order on the held-out tail, then fit the whole record.

        Parameters
        ----------
        u, y : array_like, shape (n,)
            Input and output (any units), finite, ``n >= 100``, not constant.

        Returns
        -------
        self
        """
        ua, ya = check_record(u, y, _OWNER, MIN_SAMPLES, varying=True)
        p = self._validated()
        sel = select_structure(
            ua,
            ya,
            max_order=p["max_order"],
            order=p["order"],
            n_knots=2,
            validation_fraction=p["validation_fraction"],
        )
        if sel is None:
            raise InvalidValueError(
                f"The 'y' parameter of {_OWNER} must be explained by a stable linear model of "
                "some order. Got no stable fit instead."
            )
        self._set_state(baseline_fit(ua, ya, sel, p["n_lags"], self._freeze()))
        return self

    def _check_fitted(self) -> LinearModel:
        return self._fitted_state().model

    @property
    def model_(self) -> LinearModel:
        """The fitted model."""
        return self._check_fitted()

    @property
    def selection_(self) -> Selection | None:
        """The orders tried and their held-out errors (None after loading)."""
        return self._fitted_state().selection

    @property
    def n_samples_(self) -> int:
        """Samples of the record."""
        return self._fitted_state().n_samples

    @property
    def order_(self) -> int:
        """The order ``l`` in use."""
        return self._check_fitted().order

    @property
    def arma_(self) -> ARMA:
        """The linear part, from ``u - input_mean_`` to ``y - offset_``."""
        return self._check_fitted().arma

    @property
    def offset_(self) -> float:
        """Output offset (units of ``y``)."""
        return self._check_fitted().offset

    @property
    def input_mean_(self) -> float:
        """Input level of zero response (units of ``u``)."""
        return self._check_fitted().input_mean

    @property
    def estimator_(self) -> str:
        """``"least squares"`` or ``"instrumental variables"``."""
        return self._check_fitted().estimator

    @property
    def impulse_response_(self) -> F64:
        """The impulse response, shape (n_lags,) (units of ``y`` per unit of ``u``)."""
        fit = self._fitted_state()
        return fit.model.arma.impulse_response(fit.n_lags)

    def predict(
        self, u: ArrayLike, y: ArrayLike | None = None, steps_ahead: int | None = None
    ) -> F64:
        """Free run from rest, from initial conditions ``y[:m]``, or k steps ahead.

        Parameters
        ----------
        u : array_like, shape (n,)
            Input (units of ``u``).
        y : array_like, shape (n,), optional
            Measured output: its first ``m = max(p, q)`` samples are the initial
            conditions, and a k-step prediction runs on it.
        steps_ahead : int, optional
            ``k >= 1``: predict ``y_n`` from the outputs measured up to ``n - k``
            (needs ``y``). None: free run.

        Returns
        -------
        ndarray, shape (n,)
            Predicted output (units of ``y``); with ``y``, the first ``m`` are ``y[:m]``.
        """
        model = self._check_fitted()
        owner = f"{_OWNER}.predict"
        ua = check_input(u, owner)
        return predict_output(
            model.arma, ua - model.input_mean, model.offset, y, steps_ahead, owner=owner
        )


def check_fraction(value: object, owner: str) -> float:
    """``validation_fraction`` in (0, 0.5]."""
    frac = check_real(value, "validation_fraction", owner, positive=True)
    if frac > 0.5:
        raise InvalidValueError(
            f"The 'validation_fraction' parameter of {owner} must be in (0, 0.5]. "
            f"Got {frac} instead."
        )
    return frac
