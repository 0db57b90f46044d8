"""Fitting the kernel estimates from chunks: any iterator of ``(X, y)``, or Dask arrays.

Both paths give, bit for bit, the state that one in-memory ``fit`` on the
concatenated samples gives (the blocked order of
:mod:`~flexarm.ident.regression.accumulators.blocks`), in memory bounded by a chunk
(times the chunks in flight) in the grid, binned and series modes; exact mode
keeps every sample by design.

* :func:`fit_iterable` — chunks in arrival order through the accumulator's
  ``add_chunk``, one at a time (what a loop of ``partial_fit`` calls does).
* :func:`fit_dask` — Dask arrays (duck-typed: an object with
  ``__dask_graph__``; Dask is imported only then, never at import time).
  The arrays are rechunked along axis 0 to chunks of a multiple of the
  block size ``B``; each chunk becomes its per-block partial sums on a
  worker (:func:`chunk_task`: a pure function of the estimate's
  :class:`~flexarm.ident.regression.accumulators.Smoothing`, the chunk and its global
  offset — plain, picklable arguments), and the client adds them in order, a
  few chunks at a time (:func:`window`), so that partials never pile up.
  Exact and binned modes receive the checked samples in order instead (exact
  mode only after a memory check: it keeps them all).

A bandwidth rule (``"silverman"``) needs every sample at once; the estimators
refuse it here, naming ``bandwidth`` (``flexarm.ident.regression._setup.smoothing``).
"""

from __future__ import annotations

import importlib
import math
import os
import sys
from collections.abc import Callable, Iterable
from typing import Any

import numpy as np

from ..._budget import check_memory
from ...errors import FlexarmError, InvalidTypeError, InvalidValueError
from ._setup import check_Xy
from .accumulators import Accumulator, BlockedAccumulator, ExactSamples, Smoothing
from .accumulators.blocks import ChunkPartials

__all__ = ["chunk_task", "fit_dask", "fit_iterable", "is_dask", "window"]

#: Starts (or returns) the estimator's accumulator for ``d`` inputs, naming the source.
Begin = Callable[[int, str], Accumulator]
#: Largest chunk of a rechunked Dask array, in blocks.
MAX_CHUNK_BLOCKS = 64


def is_dask(value: object) -> bool:
    """Whether ``value`` is a Dask collection (duck-typed: it has ``__dask_graph__``)."""
    return callable(getattr(value, "__dask_graph__", None))


def _dask(name: str) -> Any:
    """Import a Dask module (only when a Dask array is given; Dask is optional)."""
    return importlib.import_module(name)


def _in_chunk(err: FlexarmError, where: str) -> FlexarmError:
    """The same error, with the chunk it was found in."""
    return type(err)(f"{err} In {where}.")


def fit_iterable(begin: Begin, chunks: Iterable[Any], owner: str) -> Accumulator:
    """Add the ``(X, y)`` pairs of ``chunks`` in order; the accumulator.

    Parameters
    ----------
    begin : callable
        ``begin(d, source)`` starts the estimator's accumulator (first chunk).
    chunks : iterable of (array_like, array_like)
        Pairs ``X`` of shape ``(m,)`` or ``(m, d)`` (units of the regressor)
        and ``y`` of shape ``(m,)`` (units of the response); ``m`` may vary.
    owner : str
        The estimator's name, for the error messages.
    """
    if isinstance(chunks, np.ndarray | str | bytes) or not isinstance(chunks, Iterable):
        raise InvalidTypeError(
            f"The 'chunks' parameter of {owner} must be an iterable of (X, y) pairs. "
            f"Got {type(chunks).__name__} instead."
        )
    acc: Accumulator | None = None
    for k, item in enumerate(chunks):
        if not isinstance(item, tuple | list) or len(item) != 2:
            raise InvalidTypeError(
                f"The 'chunks' parameter of {owner} must yield (X, y) pairs. "
                f"Got {type(item).__name__} at position {k} instead."
            )
        start = 0 if acc is None else acc.n_samples
        try:
            X, y = check_Xy(item[0], item[1], owner)
        except FlexarmError as err:
            raise _in_chunk(err, f"chunk {k} (from sample {start})") from None
        if acc is None:
            acc = begin(X.shape[1], "an iterator of chunks")
        elif X.shape[1] != acc.setup.d:
            raise InvalidValueError(
                f"The 'X' parameter of {owner} must be of {acc.setup.d} column(s) in every "
                f"chunk. Got {X.shape[1]} in chunk {k} instead."
            )
        acc.add_chunk(X, y)
    if acc is None:
        raise InvalidValueError(
            f"The 'chunks' parameter of {owner} must yield at least one (X, y) pair. "
            "Got none instead."
        )
    return acc


def chunk_task(kind: type[Accumulator], setup: Smoothing, X: Any, y: Any, start: int) -> Any:
    """One chunk's partials (run on a Dask worker): check the samples, sum them per block.

    A pure function of its (picklable) arguments. Chunks of the blocked modes
    that start at a multiple of the block size give their per-block partial
    sums; otherwise the checked samples themselves, which the client adds in
    order (:meth:`~flexarm.ident.regression.accumulators.Accumulator.add_partials`).
    """
    try:
        Xa, ya = check_Xy(X, y, setup.owner)
    except FlexarmError as err:
        n = np.shape(y)[0] if np.ndim(y) else 0
        raise _in_chunk(err, f"the chunk of samples {start} to {start + n - 1}") from None
    if issubclass(kind, BlockedAccumulator) and start % setup.block == 0:
        return kind.chunk_partials(setup, Xa, ya, start)
    return ChunkPartials(start, Xa.shape[0], ({"X": Xa, "y": ya},))


def window() -> int:
    """Chunks computed at once: twice the Dask client's threads, or this machine's cores."""
    threads = os.cpu_count() or 1
    if "distributed" in sys.modules:  # a client is active only if distributed was imported
        try:
            client = importlib.import_module("distributed").default_client()
            threads = sum(client.nthreads().values())
        except (ImportError, ValueError):
            pass
    return max(2, 2 * threads)


def _check_dask(X: Any, y: Any, owner: str) -> tuple[Any, Any, int, int]:
    """Both as Dask arrays, with their shapes checked from the metadata; ``n``, ``d``."""
    da = _dask("dask.array")
    X = X if is_dask(X) else da.asarray(np.asarray(X))
    y = y if is_dask(y) else da.asarray(np.asarray(y))
    for name, arr in (("X", X), ("y", y)):
        kind = getattr(arr, "dtype", np.dtype(object)).kind
        if kind == "c":
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be real. Got complex instead."
            )
        if kind not in "biuf":
            raise InvalidTypeError(
                f"The '{name}' parameter of {owner} must be a numeric array. "
                f"Got dtype {getattr(arr, 'dtype', type(arr).__name__)} instead."
            )
        if any(math.isnan(s) for s in arr.shape):
            raise InvalidValueError(
                f"The '{name}' parameter of {owner} must have known chunk sizes "
                f"(call {name}.compute_chunk_sizes()). Got shape {arr.shape} instead."
            )
    if X.ndim not in (1, 2) or (X.ndim == 2 and X.shape[1] < 1):
        raise InvalidValueError(
            f"The 'X' parameter of {owner} must be of shape (n,) or (n, d). "
            f"Got shape {X.shape} instead."
        )
    if y.ndim != 1:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must be of shape (n,). Got shape {y.shape} instead."
        )
    n = int(X.shape[0])
    if y.shape[0] != n:
        raise InvalidValueError(
            f"The 'y' parameter of {owner} must be of length {n} (the rows of X). "
            f"Got length {y.shape[0]} instead."
        )
    if n == 0:
        raise InvalidValueError(
            f"The 'X' parameter of {owner} must have at least one sample. Got 0 samples instead."
        )
    return X, y, n, 1 if X.ndim == 1 else int(X.shape[1])


def _chunk_sizes(n0: int, n: int, block: int, given: int) -> tuple[int, ...]:
    """Chunks for samples ``n0 + 1 .. n0 + n``: the rest of the open block, then whole
    multiples of ``block`` (about the given chunk size, at most ``MAX_CHUNK_BLOCKS``)."""
    size = block * max(1, min(MAX_CHUNK_BLOCKS, round(given / block)))
    first = min(n, -n0 % block)
    sizes = [first] if first else []
    rest = n - first
    sizes += [size] * (rest // size) + ([rest % size] if rest % size else [])
    return tuple(sizes)


def fit_dask(begin: Begin, X: Any, y: Any, owner: str) -> Accumulator:
    """Add the samples of Dask arrays ``X`` (shape ``(n,)`` or ``(n, d)``) and ``y`` (``(n,)``).

    Continues the accumulator ``begin`` returns (a fresh one for ``fit``, the
    current one for ``partial_fit``). Each chunk is computed where Dask's
    scheduler puts it (threads, processes, a ``distributed`` cluster); the
    combination is in order on the client, bit for bit as one in-memory fit.
    """
    dask = _dask("dask")
    X, y, n, d = _check_dask(X, y, owner)
    acc = begin(d, "a Dask array")
    setup = acc.setup
    if isinstance(acc, ExactSamples):
        check_memory(
            2.0 * (acc.n_samples + n) * (2 * d + 2) * 8,
            f"fitting {n} samples in exact mode (grid=None keeps every sample)",
            owner,
            "Give a grid (grid mode keeps O(grid) memory for any number of samples)",
        )
    given = int(max(X.chunks[0]))
    sizes = _chunk_sizes(acc.n_samples, n, setup.block, given)
    X = X.rechunk({0: sizes, 1: -1} if X.ndim == 2 else {0: sizes})
    y = y.rechunk({0: sizes})
    # unoptimised: the chunks of X and y keep the tasks they share (computed once)
    xs = X.to_delayed(optimize_graph=False).ravel()
    ys = y.to_delayed(optimize_graph=False).ravel()
    starts = acc.n_samples + np.concatenate([[0], np.cumsum(sizes)[:-1]]).astype(np.int64)
    task = dask.delayed(chunk_task, pure=False)
    step = window()
    kind = type(acc)
    for w in range(0, len(sizes), step):
        todo = range(w, min(len(sizes), w + step))
        parts = dask.compute(*[task(kind, setup, xs[k], ys[k], int(starts[k])) for k in todo])
        for part in parts:
            acc.add_partials(part)
    return acc
