"""Numba compilation options shared by the hot compiled functions."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

import numba as nb

__all__ = ["RUNTIME_FREE", "compiled_as", "njit_runtime_free"]


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


def njit_runtime_free(*signatures: Any, **options: Any) -> Callable[[_Fn], _Fn]:
    """``numba.njit(*signatures, **options)`` compiled without the refcount runtime
    where this Numba supports it (for hot functions that allocate nothing).

    ``signatures`` (optional, a list of Numba signatures) compiles those eagerly and
    no others: a call with other argument types raises TypeError.
    """
    decorator: Callable[[_Fn], _Fn] = nb.njit(*signatures, **options, **RUNTIME_FREE)  # type: ignore[call-overload]
    return decorator


def compiled_as(public: Callable[..., Any], *, runtime_free: bool = False) -> Callable[[_Fn], _Fn]:
    """Register the decorated function as ``public``'s implementation inside compiled
    code (a Numba ``overload``, cached and without the GIL; not inlined, which links
    the kernel into a user's function in about a second instead of re-optimising it
    there for ten).

    The pattern of flexarm's public kernels: ``public`` is a Python function (the
    checked face) that checks its arguments and calls the bare ``@njit`` kernel of an
    internal module; the decorated function returns that kernel for compiled
    callers, who get it unchecked::

        @compiled_as(forward_dynamics)
        def _(q, dq, tau, model, ws, ddq):
            return lambda q, dq, tau, model, ws, ddq: _forward.forward_dynamics(
                q, dq, tau, model, ws, ddq
            )

    With ``runtime_free`` the implementation is compiled without the refcount
    runtime (:func:`njit_runtime_free`; for kernels that allocate nothing): its
    array arguments then cross the call without atomic incref/decref pairs,
    which otherwise cost a kernel of ~30 arrays hundreds of ns a call whenever
    LLVM does not inline it into its caller.
    """
    from numba.extending import overload

    options: Any = {"cache": True, "nogil": True}  # numba's stub lists no "cache"
    if runtime_free:
        options.update(RUNTIME_FREE)
    register: Callable[[_Fn], _Fn] = overload(public, jit_options=options)
    return register
