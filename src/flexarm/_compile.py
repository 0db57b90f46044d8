"""Numba compilation options shared by the hot compiled functions."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba as nb

__all__ = ["RUNTIME_FREE", "njit_runtime_free"]


def _runtime_free_options() -> dict[str, bool]:
    """Numba options that compile a function without its reference-counting
    runtime (NRT), for hot functions that allocate nothing.

    Array arguments are then passed without atomic incref/decref calls, which
    cost the dynamics kernel ~40 % of its time. ``_nrt`` is a Numba target
    option of long standing but not a documented one, so it is used only where
    this Numba version lists it.
    """
    from numba.core import cpu

    return {"_nrt": False} if hasattr(cpu.CPUTargetOptions, "_nrt") else {}


RUNTIME_FREE = _runtime_free_options()


_Fn = TypeVar("_Fn", bound=Callable[..., Any])


def njit_runtime_free(**options: Any) -> Callable[[_Fn], _Fn]:
    """``numba.njit(**options)`` compiled without the refcount runtime where
    this Numba supports it (for hot functions that allocate nothing)."""
    decorator: Callable[[_Fn], _Fn] = nb.njit(**options, **RUNTIME_FREE)  # type: ignore[call-overload]
    return decorator
