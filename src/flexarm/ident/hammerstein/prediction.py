r"""Free-run and k-step-ahead prediction of identified models, and their scores.

An identified model here is ``y = offset + B(q)/A(q) w`` with ``w`` a known
static function of the input (``phi_hat(u)`` for a Hammerstein model, ``u``
for a linear one) and the linear part in the paper's ARMA convention
(:class:`~flexarm.ident.hammerstein.systems.ARMA`). :func:`predict_output` follows
sysidentpy's convention:

* ``y=None``: the **free run** from rest, ``offset + ARMA.filter(w)``;
* ``y`` given, ``steps_ahead=None``: the free run from the initial conditions
  ``y[:m]`` (``m = max(p, q)``, the model's largest lag; those samples are
  returned as given);
* ``y`` given, ``steps_ahead=k``: the ``k``-step-ahead prediction
  ``y_hat_{n | n-k}`` — the recursion restarted from the measured outputs up to
  ``n - k`` (``k = 1``: one step ahead, the equation-error predictor).

Inputs before the first sample count as zero in every mode.

Scores: :func:`r2_score` (scikit-learn's ``score``) and
:func:`fit_percent`.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from ..._types import F64
from ..._validation import check_array, check_int
from ...errors import InvalidTypeError, InvalidValueError
from .systems import ARMA

__all__ = [
    "Scored",
    "check_input",
    "check_record",
    "check_steps",
    "fit_percent",
    "max_lag",
    "predict_output",
    "r2_score",
]


def check_input(u: ArrayLike, owner: str, name: str = "u") -> F64:
    """A real, finite, 1-D array of float64 (the message names ``name`` and ``owner``)."""
    arr = check_array(u, name, owner)
    if arr.dtype.kind == "c":
        raise InvalidTypeError(f"The '{name}' parameter of {owner} must be real. Got complex.")
    if arr.ndim != 1:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must be of shape (n,). "
            f"Got shape {arr.shape} instead."
        )
    return np.ascontiguousarray(arr, dtype=np.float64)


def check_record(
    u: ArrayLike, y: ArrayLike, owner: str, minimum: int = 1, *, varying: bool = False
) -> tuple[F64, F64]:
    """Input and output of one record: real, finite, 1-D, of one length ``>= minimum``.

    With ``varying``, a constant input or output is refused too.
    """
    ua = check_input(u, owner, "u")
    ya = check_input(y, owner, "y")
    if ya.shape[0] != ua.shape[0]:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must have the length of u ({ua.shape[0]}). "
            f"Got length {ya.shape[0]} instead."
        )
    if ua.shape[0] < minimum:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must hold at least {minimum} samples. "
            f"Got {ua.shape[0]} instead."
        )
    if varying and np.ptp(ua) == 0.0:
        raise InvalidValueError(
            f"The 'u' parameter of {owner} must vary. Got a constant input instead."
        )
    if varying and np.ptp(ya) == 0.0:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must vary with the input. Got a constant output."
        )
    return ua, ya


def max_lag(arma: ARMA) -> int:
    """``m = max(p, q)``: the initial conditions a prediction from data takes."""
    p, q = arma.order
    return max(p, q)


def check_steps(steps_ahead: object, owner: str) -> int | None:
    """``steps_ahead``: None (free run) or an integer >= 1."""
    if steps_ahead is None:
        return None
    return check_int(steps_ahead, "steps_ahead", owner, minimum=1)


def predict_output(
    arma: ARMA,
    w: F64,
    offset: float,
    y: ArrayLike | None = None,
    steps_ahead: int | None = None,
    *,
    owner: str,
) -> F64:
    """Output of ``offset + B/A w``: free run, or from data (module docstring).

    Parameters
    ----------
    arma : ARMA
        The linear part.
    w : ndarray, shape (n,)
        Its input (the static part applied to the model input).
    offset : float
        Output offset (units of ``y``).
    y : array_like, shape (n,), optional
        Measured outputs: initial conditions, and the data of a k-step prediction.
    steps_ahead : int, optional
        ``k >= 1`` for the k-step-ahead prediction (needs ``y``); None: free run.
    owner : str
        Named in the error messages (``"HammersteinIdentifier.predict"``).

    Returns
    -------
    ndarray, shape (n,)
        Predicted output (units of ``y``).
    """
    steps = check_steps(steps_ahead, owner)
    if y is None:
        if steps is not None:
            raise InvalidValueError(
                f"The 'y' parameter of {owner} must be given with steps_ahead = {steps} "
                "(a k-step prediction runs on the measured outputs). Got None instead."
            )
        return arma.filter(w) + offset
    ya = check_input(y, owner, "y")
    if ya.shape != w.shape:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must be of shape {w.shape} like u. "
            f"Got shape {ya.shape} instead."
        )
    from ._loops import arma_predict

    a = np.asarray(arma.a, dtype=np.float64)
    b = np.asarray(arma.b, dtype=np.float64)
    d = np.ascontiguousarray(ya - offset, dtype=np.float64)
    out = np.empty(w.shape[0])
    arma_predict(
        a, b, np.ascontiguousarray(w), d, max_lag(arma), 0 if steps is None else steps, out
    )
    result: F64 = out + offset
    return result


def _residuals(
    y: ArrayLike, y_hat: ArrayLike, owner: str, size: Callable[[F64], float]
) -> tuple[float, float]:
    """``size(y - y_hat)`` and ``size(y - mean y)`` of a score (``y`` must vary)."""
    ya = check_array(y, "y", owner, shape=(-1,))
    yh = check_array(y_hat, "y_hat", owner, shape=ya.shape)
    spread = size(ya - ya.mean())
    if spread == 0.0:
        raise InvalidValueError(f"The 'y' parameter of {owner} must vary. Got a constant instead.")
    return size(ya - yh), spread


def fit_percent(y: ArrayLike, y_hat: ArrayLike) -> float:
    """Fit in percent, ``100 (1 - ||y - y_hat|| / ||y - mean(y)||)`` (100 is perfect).

    Parameters
    ----------
    y : array_like, shape (n,)
        Measured output.
    y_hat : array_like, shape (n,)
        Model output, same units.

    Examples
    --------
    >>> fit_percent([1.0, 2.0, 3.0], [1.0, 2.0, 3.0])
    100.0
    """
    error, spread = _residuals(y, y_hat, "fit_percent", lambda r: float(np.linalg.norm(r)))
    return 100.0 * (1.0 - error / spread)


def r2_score(y: ArrayLike, y_hat: ArrayLike) -> float:
    """Coefficient of determination ``1 - ||y - y_hat||**2 / ||y - mean(y)||**2`` (1: perfect).

    Parameters
    ----------
    y : array_like, shape (n,)
        Measured output.
    y_hat : array_like, shape (n,)
        Model output, same units.

    Examples
    --------
    >>> r2_score([1.0, 2.0, 3.0], [1.0, 2.0, 4.0])
    0.5
    """
    error, spread = _residuals(y, y_hat, "r2_score", lambda r: float(np.sum(r**2)))
    return 1.0 - error / spread


class Scored:
    """``score`` and ``fit_percent`` of an identified model, from its ``predict``."""

    def predict(
        self, u: ArrayLike, y: ArrayLike | None = None, steps_ahead: int | None = None
    ) -> F64:
        """The model's output for the input ``u`` (free run, or from the measured ``y``)."""
        raise NotImplementedError  # pragma: no cover - every model defines it

    def score(self, u: ArrayLike, y: ArrayLike, steps_ahead: int | None = None) -> float:
        """R² of :meth:`predict` on ``(u, y)`` (scikit-learn's ``score``; 1 is perfect).

        With ``steps_ahead``, of the k-step prediction; otherwise of the free run from rest.

        Parameters
        ----------
        u, y : array_like, shape (n,)
            Input and measured output (units of ``u`` and ``y``).
        steps_ahead : int, optional
            ``k >= 1``; None: the free run.
        """
        ua, ya = check_record(u, y, f"{type(self).__name__}.score")
        return r2_score(ya, self.predict(ua, ya if steps_ahead else None, steps_ahead))

    def fit_percent(self, u: ArrayLike, y: ArrayLike, steps_ahead: int | None = None) -> float:
        """Fit in percent, ``100 (1 - ||y - y_hat|| / ||y - mean y||)``, of :meth:`predict`
        (100 is perfect); the arguments as :meth:`score`'s."""
        ua, ya = check_record(u, y, f"{type(self).__name__}.fit_percent")
        return fit_percent(ya, self.predict(ua, ya if steps_ahead else None, steps_ahead))
