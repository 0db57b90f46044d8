"""The scikit-learn hyperparameter contract shared by the estimators."""

from __future__ import annotations

import inspect
from typing import Any, Self

import numpy as np

from ..errors import InvalidValueError

__all__ = ["HyperParameters", "NotFittedError", "same_value"]


class NotFittedError(ValueError, AttributeError):
    """Raised when an estimator is used before ``fit`` (as in scikit-learn)."""


def same_value(a: Any, b: Any) -> bool:
    """Equality for hyperparameter values that may be arrays."""
    if a is b:
        return True
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        try:
            return bool(np.array_equal(np.asarray(a), np.asarray(b)))
        except Exception:  # pragma: no cover - incomparable values
            return False
    try:
        return bool(a == b)
    except Exception:  # pragma: no cover - incomparable values
        return False


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
