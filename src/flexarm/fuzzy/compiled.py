"""The compiled (Numba) evaluation of a packed fuzzy system: the simulation loop's path.

Each public function checks its arguments when called from Python (a short
scratch buffer would be written past its end) and calls a bare compiled kernel
(``flexarm.fuzzy._kernels``); inside compiled code (a controller's loop) the same
name is the kernel itself.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from .._compile import compiled_as
from ..errors import InvalidTypeError, InvalidValueError
from ._kernels import (
    CompiledFuzzySystem,
    evaluate_into_kernel,
    evaluate_kernel,
    evaluate_many_kernel,
    unpack_system_kernel,
    workspace_size_kernel,
)

__all__ = [
    "CompiledFuzzySystem",
    "evaluate",
    "evaluate_into",
    "evaluate_many",
    "pack_system",
    "unpack_system",
    "workspace_size",
]

FloatArray = NDArray[np.float64]


def pack_system(c: CompiledFuzzySystem) -> FloatArray:
    """A compiled fuzzy system as one float vector (integer arrays bit-cast), to travel
    in a compiled controller's parameter vector; :func:`unpack_system` reads it back."""

    def ints(a: NDArray[np.int64]) -> FloatArray:
        return np.ascontiguousarray(a, dtype=np.int64).ravel().view(np.float64)

    sizes = np.array(
        [c.term_type.size, c.rule_ante.shape[0], c.rule_ante.shape[1], c.out_par.shape[0]],
        dtype=np.int64,
    )
    return np.concatenate(
        [
            ints(sizes),
            ints(c.term_type),
            c.term_par.ravel(),
            ints(c.term_input),
            c.input_bounds.ravel(),
            ints(c.rule_ante),
            ints(c.rule_cons),
            c.out_par.ravel(),
            ints(c.ops),
            c.out_range.ravel(),
        ]
    )


# ------------------------------------------------------------------ checked public faces
def _check_system(system: object, owner: str) -> int:
    """The number of inputs of a consistent :class:`CompiledFuzzySystem`."""
    if not isinstance(system, CompiledFuzzySystem):
        raise InvalidTypeError(
            f"The 'system' parameter of {owner} must be a CompiledFuzzySystem "
            f"(FuzzySystem.compiled()). Got {type(system).__name__} instead."
        )
    arrays = {name: getattr(system, name) for name in CompiledFuzzySystem._fields}
    kinds = {"term_type": "i", "term_input": "i", "rule_ante": "i", "rule_cons": "i", "ops": "i"}
    for name, a in arrays.items():
        if not (isinstance(a, np.ndarray) and a.flags.c_contiguous):
            raise InvalidValueError(
                f"The 'system.{name}' parameter of {owner} must be a C-contiguous array."
            )
        want = np.int64 if kinds.get(name) == "i" else np.float64
        if a.dtype != want:
            raise InvalidValueError(
                f"The 'system.{name}' parameter of {owner} must be of dtype "
                f"{np.dtype(want).name}. Got {a.dtype} instead."
            )
    n_terms = arrays["term_type"].shape[0]
    n_in = arrays["input_bounds"].shape[0]
    n_rules = arrays["rule_ante"].shape[0]
    n_out = arrays["out_par"].shape[0]
    ok = (
        arrays["term_par"].shape == (n_terms, 4)
        and arrays["term_input"].shape == (n_terms,)
        and arrays["input_bounds"].shape == (n_in, 2)
        and arrays["rule_ante"].shape == (n_rules, n_in)
        and arrays["rule_cons"].shape == (n_rules,)
        and arrays["out_par"].shape == (n_out, 4)
        and arrays["ops"].shape == (3,)
        and arrays["out_range"].shape == (3,)
        and bool(np.all((arrays["term_input"] >= 0) & (arrays["term_input"] < n_in)))
        and bool(np.all((arrays["rule_ante"] >= -1) & (arrays["rule_ante"] < n_terms)))
        and bool(np.all((arrays["rule_cons"] >= 0) & (arrays["rule_cons"] < n_out)))
    )
    if not ok:
        raise InvalidValueError(
            f"The 'system' parameter of {owner} must be consistent (as FuzzySystem.compiled() "
            "builds it): its arrays' shapes and indices do not fit together."
        )
    return int(n_in)


def _check_inputs(x: object, n_in: int, owner: str, batch: bool) -> None:
    shape = f"(m, {n_in})" if batch else f"({n_in},)"
    if not (isinstance(x, np.ndarray) and x.dtype == np.float64 and x.flags.c_contiguous):
        raise InvalidValueError(
            f"The 'x' parameter of {owner} must be a C-contiguous float64 array of shape "
            f"{shape}. Got {type(x).__name__} instead."
        )
    if (x.ndim, x.shape[-1] if x.ndim else -1) != ((2 if batch else 1), n_in):
        raise InvalidValueError(
            f"The 'x' parameter of {owner} must be of shape {shape}. Got shape {x.shape} instead."
        )


def workspace_size(system: CompiledFuzzySystem) -> int:
    """Length of the scratch buffer :func:`evaluate_into` needs for ``system``."""
    _check_system(system, "workspace_size")
    return int(workspace_size_kernel(system))


def evaluate(system: CompiledFuzzySystem, x: FloatArray) -> float:
    """Compiled centroid output of a packed system at one input vector ``x`` (shape
    (n_in,)); checked."""
    n_in = _check_system(system, "evaluate")
    _check_inputs(x, n_in, "evaluate", batch=False)
    return float(evaluate_kernel(system, x))


def evaluate_into(system: CompiledFuzzySystem, x: FloatArray, buf: FloatArray) -> float:
    """:func:`evaluate` with caller-owned scratch ``buf`` of at least
    :func:`workspace_size` entries; checked."""
    owner = "evaluate_into"
    n_in = _check_system(system, owner)
    _check_inputs(x, n_in, owner, batch=False)
    need = int(workspace_size_kernel(system))
    if not (
        isinstance(buf, np.ndarray)
        and buf.dtype == np.float64
        and buf.ndim == 1
        and buf.flags.c_contiguous
        and buf.flags.writeable
        and buf.shape[0] >= need
    ):
        raise InvalidValueError(
            f"The 'buf' parameter of {owner} must be a writable, C-contiguous float64 array "
            f"of at least {need} entries (workspace_size(system)). Got "
            f"{getattr(buf, 'shape', type(buf).__name__)} instead."
        )
    return float(evaluate_into_kernel(system, x, buf))


def evaluate_many(system: CompiledFuzzySystem, x: FloatArray) -> FloatArray:
    """:func:`evaluate` on each row of ``x`` (shape (m, n_in)); returns (m,); checked."""
    n_in = _check_system(system, "evaluate_many")
    _check_inputs(x, n_in, "evaluate_many", batch=True)
    out: FloatArray = evaluate_many_kernel(system, x)
    return out


def unpack_system(p: FloatArray, o: int) -> CompiledFuzzySystem:
    """Views of ``p[o:]`` (:func:`pack_system`'s vector) as a system; checked."""
    if not (isinstance(p, np.ndarray) and p.dtype == np.float64 and p.ndim == 1):
        raise InvalidValueError(
            "The 'p' parameter of unpack_system must be a float64 vector (pack_system)."
        )
    if not (int(o) >= 0 and int(o) + 4 <= p.shape[0]):
        raise InvalidValueError(
            f"The 'o' parameter of unpack_system must be in [0, {p.shape[0] - 4}]."
        )
    nt, nr, ni, nk = (int(v) for v in p[int(o) : int(o) + 4].view(np.int64))
    need = 4 + nt + 4 * nt + nt + 2 * ni + nr * ni + nr + 4 * nk + 3 + 3
    if min(nt, nr, ni, nk) < 0 or int(o) + need > p.shape[0]:
        raise InvalidValueError(
            "The 'p' parameter of unpack_system must hold a packed system at 'o'. Got a "
            "vector too short for the sizes it states instead."
        )
    system: CompiledFuzzySystem = unpack_system_kernel(p, int(o))
    _check_system(system, "unpack_system")
    return system


@compiled_as(workspace_size)
def _workspace_size_compiled(system):  # type: ignore[no-untyped-def]
    return lambda system: workspace_size_kernel(system)


@compiled_as(evaluate)
def _evaluate_compiled(system, x):  # type: ignore[no-untyped-def]
    return lambda system, x: evaluate_kernel(system, x)


@compiled_as(evaluate_into)
def _evaluate_into_compiled(system, x, buf):  # type: ignore[no-untyped-def]
    return lambda system, x, buf: evaluate_into_kernel(system, x, buf)


@compiled_as(evaluate_many)
def _evaluate_many_compiled(system, x):  # type: ignore[no-untyped-def]
    return lambda system, x: evaluate_many_kernel(system, x)


@compiled_as(unpack_system)
def _unpack_system_compiled(p, o):  # type: ignore[no-untyped-def]
    return lambda p, o: unpack_system_kernel(p, o)
