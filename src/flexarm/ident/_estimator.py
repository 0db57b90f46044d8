"""The estimator contract of both families: hyperparameters, one fitted state, one change rule.

* :class:`HyperParameters` — scikit-learn's contract: the constructor only stores
  its arguments under their own names, ``get_params`` / ``set_params`` / ``repr``
  follow from its signature (so :func:`sklearn.base.clone` works), and the fit
  checks them.
* :class:`Estimator` — what a fit leaves is one frozen value, :attr:`~Estimator.state_`,
  of a dataclass derived from :class:`Fitted` (one per estimator:
  :class:`~flexarm.ident.regression.estimators.RegressionState`,
  :class:`~flexarm.ident.hammerstein.identifier.HammersteinState`,
  :class:`~flexarm.ident.hammerstein.linear.LinearFit`); every one of them starts
  with the hyperparameters as the first fit found them, copied (arrays and
  sequences too), and :meth:`Estimator.from_state` rebuilds an estimator from it.
* :class:`SavedEstimator` — an estimator whose state is also a set of plain
  arrays (:meth:`~SavedEstimator.to_arrays`, :meth:`~SavedEstimator.from_arrays`),
  written to and read from one ``.npz`` file (no pickle).

**Parameters changed.** A streaming fit (``partial_fit``) continues only while
every hyperparameter has the value the first fit froze; otherwise it refuses,
naming them. Values are compared as values (:func:`same_value`): numbers and
strings by ``==``, arrays element by element, lists and tuples entry by entry. A
comparison of ``repr`` would miss a change in the middle of a long array (NumPy
elides it) and see one between ``1`` and ``1.0``; a frozen reference to the
object itself would miss a change made in place.
"""

from __future__ import annotations

import copy
import inspect
import os
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar, Generic, Self, TypeVar

import numpy as np
from numpy.typing import NDArray

from .._io import atomic_path
from ..errors import InvalidValueError

__all__ = [
    "Arrays",
    "Estimator",
    "Fitted",
    "HyperParameters",
    "NotFittedError",
    "SavedEstimator",
    "callable_output",
    "frozen_copy",
    "frozen_params",
    "same_value",
]

#: A state as plain arrays: what an estimator's file holds.
Arrays = dict[str, NDArray[Any]]


class NotFittedError(ValueError, AttributeError):
    """Raised when an estimator is used before ``fit`` (as in scikit-learn)."""


def callable_output(
    value: Any, name: str, owner: str, shape: tuple[int, ...], expected: str
) -> NDArray[np.float64]:
    """What the user's callable ``name`` returned, as floats, checked: of ``shape`` (else
    an error saying it must return ``expected``) and finite."""
    w = np.asarray(value, dtype=np.float64)
    if w.shape != shape:
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must return {expected}. "
            f"Got shape {w.shape} instead."
        )
    if not np.all(np.isfinite(w)):
        raise InvalidValueError(
            f"The '{name}' parameter of {owner} must return finite values. "
            "Got non-finite values instead."
        )
    return w


def same_value(a: Any, b: Any) -> bool:
    """Whether two hyperparameter values are the same value (module docstring)."""
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        try:
            return bool(np.array_equal(np.asarray(a), np.asarray(b)))
        except Exception:  # pragma: no cover - incomparable values
            return False
    if isinstance(a, list | tuple) and type(a) is type(b):
        return len(a) == len(b) and all(same_value(x, y) for x, y in zip(a, b, strict=True))
    try:
        return bool(a == b)
    except Exception:  # pragma: no cover - incomparable values
        return False


def frozen_copy(value: Any) -> Any:
    """``value`` as a fit freezes it: arrays, lists and tuples deep-copied, the rest as is."""
    return copy.deepcopy(value) if isinstance(value, np.ndarray | list | tuple) else value


def frozen_params(est: HyperParameters) -> dict[str, Any]:
    """The hyperparameters of ``est`` as a fit freezes them (:attr:`Fitted.params`)."""
    return {k: frozen_copy(v) for k, v in est.get_params().items()}


class HyperParameters:
    """``get_params`` / ``set_params`` / ``repr`` from the ``__init__`` signature.

    The constructor only stores its arguments under their own names (checked at
    fit time), so :func:`sklearn.base.clone` works.
    """

    @classmethod
    def _get_param_names(cls) -> list[str]:
        sig = inspect.signature(cls.__init__)
        return sorted(p.name for p in sig.parameters.values() if p.name != "self")

    def get_params(self, deep: bool = True) -> dict[str, Any]:
        """Return the hyperparameters as a dict (``deep`` is accepted for scikit-learn)."""
        return {name: getattr(self, name) for name in self._get_param_names()}

    def set_params(self, **params: Any) -> Self:
        """Set hyperparameters by name and return ``self``; they are checked at fit time."""
        valid = self._get_param_names()
        for name, value in params.items():
            if name not in valid:
                raise InvalidValueError(
                    f"Invalid parameter {name!r} for estimator {type(self).__name__}. "
                    f"Valid parameters are: {valid}."
                )
            setattr(self, name, value)
        return self

    def __repr__(self) -> str:
        defaults = {
            p.name: p.default
            for p in inspect.signature(type(self).__init__).parameters.values()
            if p.name != "self"
        }
        with np.printoptions(threshold=6, edgeitems=2):
            shown = [
                f"{k}={v!r}"
                for k, v in self.get_params().items()
                if not same_value(v, defaults.get(k))
            ]
        return f"{type(self).__name__}({', '.join(shown)})"


@dataclass(frozen=True)
class Fitted:
    """The start of every fitted state: the hyperparameters the first fit froze.

    Attributes
    ----------
    params : dict
        ``get_params()`` at the first ``fit`` or ``partial_fit``, arrays and
        sequences copied (:func:`frozen_copy`): the constructor's arguments of
        :meth:`Estimator.from_state`.
    """

    params: dict[str, Any]


S = TypeVar("S", bound=Fitted)


class Estimator(HyperParameters, Generic[S]):
    """An estimator whose fit leaves one frozen state (module docstring)."""

    #: What the not-fitted error tells the caller to do.
    _not_fitted_hint: ClassVar[str] = (
        "Call 'fit' or 'partial_fit' with appropriate arguments before using this estimator."
    )

    @property
    def _owner(self) -> str:
        return type(self).__name__

    def _fitted_state(self, hint: str | None = None) -> S:
        """The fitted state; :class:`NotFittedError` (with ``hint``) before a fit."""
        state: S | None = self.__dict__.get("_fitted")
        if state is None:
            raise NotFittedError(
                f"This {self._owner} instance is not fitted yet. "
                f"{self._not_fitted_hint if hint is None else hint}"
            )
        return state

    def _is_fitted(self) -> bool:
        return self.__dict__.get("_fitted") is not None

    def _set_state(self, state: S) -> None:
        self.__dict__["_fitted"] = state

    def _forget(self) -> None:
        self.__dict__.pop("_fitted", None)

    def _freeze(self) -> dict[str, Any]:
        return frozen_params(self)

    def _check_unchanged(self, state: Fitted) -> None:
        """Refuse to continue a streaming fit if a hyperparameter changed (module docstring)."""
        now = self.get_params()
        changed = sorted(k for k in now if not same_value(now[k], state.params[k]))
        if changed:
            raise InvalidValueError(
                f"The {changed} parameter(s) of {self._owner} changed since the first "
                "partial_fit. Got new values instead; call fit to start again."
            )

    @property
    def state_(self) -> S:
        """The fitted state: one frozen dataclass (its hyperparameters first).

        Its fields are fixed by the fit; streaming sums inside it grow with
        ``partial_fit``.
        """
        return self._fitted_state()

    @classmethod
    def from_state(cls, state: S) -> Self:
        """An estimator with the hyperparameters and the fitted state ``state``.

        Parameters
        ----------
        state : Fitted
            A state of this class (:attr:`state_`).

        Returns
        -------
        estimator
            Fitted; its hyperparameters are copies of ``state.params``.
        """
        est = cls(**{k: frozen_copy(v) for k, v in state.params.items()})
        est._set_state(state)
        return est


class SavedEstimator(Estimator[S]):
    """An estimator whose state is also plain arrays, saved to and loaded from a file."""

    def to_arrays(self) -> Arrays:
        """The hyperparameters and the fitted state as plain arrays (what :meth:`save` writes).

        Returns
        -------
        dict of str to ndarray
        """
        raise NotImplementedError  # pragma: no cover - every estimator defines it

    @classmethod
    def from_arrays(cls, data: Mapping[str, NDArray[Any]]) -> Self:
        """The estimator :meth:`to_arrays` described (what :meth:`load` reads).

        Parameters
        ----------
        data : mapping of str to ndarray
            :meth:`to_arrays` output, or the arrays of a file :meth:`save` wrote.

        Returns
        -------
        estimator
            Fitted, with the state it had.
        """
        raise NotImplementedError  # pragma: no cover - every estimator defines it

    def save(self, path: str | os.PathLike[str]) -> None:
        """Write :meth:`to_arrays` to ``path`` (NumPy ``.npz``, plain arrays, no pickle).

        :meth:`load` then resumes exactly: ``partial_fit`` after ``load`` gives,
        bit for bit, what it would have given without stopping.

        Parameters
        ----------
        path : str or os.PathLike
            Destination file, written as given (no suffix is added), atomically:
            a temporary file beside it is renamed into place once complete.
        """
        arrays: dict[str, Any] = self.to_arrays()
        with atomic_path(path) as tmp, open(tmp, "wb") as f:
            np.savez(f, **arrays)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> Self:
        """Read an estimator written by :meth:`save` (of this same class).

        Parameters
        ----------
        path : str or os.PathLike
            File written by :meth:`save`.

        Returns
        -------
        estimator
            Fitted, with the state it had when saved.
        """
        with np.load(path, allow_pickle=False) as z:
            data = {k: z[k] for k in z.files}
        return cls.from_arrays(data)
