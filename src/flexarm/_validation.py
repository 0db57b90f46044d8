"""Input checks shared by every public constructor and function.

Every message names the parameter, the owner, what was expected and what was
got, in one format::

    The 'length' parameter of Link must be > 0. Got -1.0 instead.

Wrong types raise :class:`TypeError` (a switch that is not a bool included:
:func:`check_bool`); wrong values or shapes raise :class:`ValueError`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Iterable, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .errors import InvalidTypeError, InvalidValueError

__all__ = [
    "check_array",
    "check_bool",
    "check_int",
    "check_option",
    "check_real",
    "check_rng",
    "check_sequence_of",
    "validate_real_fields",
]


class _Described(str):
    """A description of the value got, printed without quotes."""

    def __repr__(self) -> str:
        return str(self)


def _fail(name: str, owner: str, expected: str, got: Any) -> str:
    return f"The '{name}' parameter of {owner} must be {expected}. Got {got!r} instead."


def _shape_text(shape: tuple[int, ...]) -> str:
    parts = ["any" if s == -1 else str(s) for s in shape]
    return "(" + ", ".join(parts) + (",)" if len(parts) == 1 else ")")


def check_real(
    value: Any,
    name: str,
    owner: str,
    *,
    positive: bool = False,
    nonnegative: bool = False,
) -> float:
    """Return ``value`` as a finite Python float, or raise.

    Parameters
    ----------
    value : Any
        The candidate number. Booleans are rejected (they are numbers in Python
        only by accident).
    name, owner : str
        Parameter and owner named in the error message.
    positive, nonnegative : bool
        Require ``value > 0`` or ``value >= 0``.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        if isinstance(value, np.ndarray) and value.ndim == 0 and value.dtype.kind in "fiu":
            value = value.item()
        else:
            raise InvalidTypeError(_fail(name, owner, "a real number", value))
    x = float(value)
    if not math.isfinite(x):
        raise InvalidValueError(_fail(name, owner, "finite", x))
    if positive and not x > 0.0:
        raise InvalidValueError(_fail(name, owner, "> 0", x))
    if nonnegative and not x >= 0.0:
        raise InvalidValueError(_fail(name, owner, ">= 0", x))
    return x


def validate_real_fields(
    obj: Any,
    owner: str,
    *,
    positive: Iterable[str] = (),
    nonnegative: Iterable[str] = (),
) -> None:
    """Check the named fields of a frozen dataclass and store them as floats."""
    for names, kind in ((positive, "positive"), (nonnegative, "nonnegative")):
        for name in names:
            value = check_real(getattr(obj, name), name, owner, **{kind: True})
            object.__setattr__(obj, name, value)


def check_sequence_of(
    value: Any, name: str, owner: str, types: type | tuple[type, ...], what: str
) -> tuple[Any, ...]:
    """Return ``value`` as a tuple whose items are all instances of ``types``.

    A single instance is accepted as a one-item sequence. ``what`` names the
    item types in the message ("Link", "LinearJoint or NonlinearJoint").
    """
    if isinstance(value, types):
        return (value,)
    if not isinstance(value, Sequence) or isinstance(value, str):
        raise InvalidTypeError(
            _fail(name, owner, f"a sequence of {what}", _Described(type(value).__name__))
        )
    items = tuple(value)
    for k, item in enumerate(items):
        if not isinstance(item, types):
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must hold {what} objects. "
                f"Got {type(item).__name__} at position {k} instead."
            )
    return items


def check_int(value: Any, name: str, owner: str, *, minimum: int | None = None) -> int:
    """Return ``value`` as a Python int (no silent truncation of floats), or raise."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise InvalidTypeError(_fail(name, owner, "an integer", value))
    n = int(value)
    if minimum is not None and n < minimum:
        raise InvalidValueError(_fail(name, owner, f">= {minimum}", n))
    return n


def check_bool(value: Any, name: str, owner: str, *, optional: bool = False) -> bool | None:
    """Return ``value`` if it is a bool (or None where ``optional``), else raise
    :class:`InvalidTypeError`: a switch given as ``1``, ``"yes"`` or ``numpy.True_``
    is a wrong type, not a wrong value.

    Examples
    --------
    >>> check_bool(True, "converged", "reproduce")
    True
    >>> check_bool(1, "converged", "reproduce")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    flexarm.errors.InvalidTypeError: The 'converged' parameter of reproduce must be a bool...
    """
    if isinstance(value, bool) or (optional and value is None):
        return value
    raise InvalidTypeError(_fail(name, owner, "a bool or None" if optional else "a bool", value))


def check_option(value: Any, name: str, owner: str, options: Iterable[str]) -> str:
    """Return ``value`` if it is one of ``options``, or raise naming them all."""
    opts = tuple(options)
    if not isinstance(value, str):
        raise InvalidTypeError(_fail(name, owner, f"a str, one of {opts}", value))
    if value not in opts:
        raise InvalidValueError(_fail(name, owner, f"one of {opts}", value))
    return value


def check_array(
    value: ArrayLike,
    name: str,
    owner: str,
    *,
    shape: tuple[int, ...] | None = None,
    finite: bool = True,
    dtype: type = float,
    real: bool = False,
) -> NDArray[Any]:
    """Return ``value`` as a NumPy array of ``dtype`` with the given shape, or raise.

    ``shape`` entries of ``-1`` accept any length along that axis. Complex input
    is kept complex when ``dtype`` is float (the complex-step derivatives of the
    mass matrix rely on it), unless ``real`` is set: then it is refused.
    """
    try:
        arr = np.asarray(value)
    except Exception as exc:  # pragma: no cover - numpy raises many types here
        raise InvalidTypeError(
            _fail(name, owner, "array-like", _Described(type(value).__name__))
        ) from exc
    if arr.dtype.kind not in "biufc":
        raise InvalidTypeError(
            _fail(name, owner, "a numeric array", _Described(f"dtype {arr.dtype}"))
        )
    if arr.dtype.kind == "c" and real:
        raise InvalidTypeError(
            _fail(
                name,
                owner,
                "real",
                _Described(f"a complex {'value' if arr.ndim == 0 else 'array'}"),
            )
        )
    if arr.dtype.kind != "c":
        arr = arr.astype(dtype, copy=False)
    if shape is not None:
        ok = arr.ndim == len(shape) and all(
            s == -1 or s == a for s, a in zip(shape, arr.shape, strict=True)
        )
        if not ok:
            raise InvalidValueError(
                _fail(
                    name, owner, f"of shape {_shape_text(shape)}", _Described(f"shape {arr.shape}")
                )
            )
    if finite and not np.all(np.isfinite(arr)):
        raise InvalidValueError(
            _fail(name, owner, "finite (no NaN or inf)", _Described("non-finite entries"))
        )
    return arr


def check_rng(rng: object, owner: str) -> np.random.Generator:
    """``rng`` as a :class:`numpy.random.Generator`: a Generator as it is, ``None`` or
    an int seed through :func:`numpy.random.default_rng`; InvalidTypeError otherwise."""
    if rng is None or (isinstance(rng, int | np.integer) and not isinstance(rng, bool)):
        return np.random.default_rng(None if rng is None else int(rng))
    if isinstance(rng, np.random.Generator):
        return rng
    raise InvalidTypeError(
        f"The 'rng' parameter of {owner} must be a numpy Generator, an int seed or None. "
        f"Got {type(rng).__name__} instead."
    )
