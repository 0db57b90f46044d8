"""Many closed-loop runs at once, spread over the machine's cores.

:func:`simulate_many` runs a list of simulations on a pool of threads. Each
run's compiled loop releases the GIL (:func:`flexarm.sim.loop.run` is compiled
with ``nogil``), so the loops of different runs proceed on different cores,
while the set-up of one run (in Python) overlaps the loops of the others.
Every run is exactly the call :func:`flexarm.simulate` would make alone, in a
thread of its own: its result is bit for bit the same as that run done alone.

:func:`iter_simulations` is the same as a generator that yields each outcome as
it completes and holds at most a few runs in flight, so that thousands of runs
(a sweep) keep only what the caller keeps.

A run is either a mapping of :func:`flexarm.simulate`'s arguments (``arm`` and
any keywords: ``{"arm": arm, "dt": 1e-4, "rng": 7}``) or a callable with no
arguments that returns a :class:`~flexarm.sim.results.SimulationResult` (e.g.
``functools.partial(flexarm.simulate_open_loop, arm, t, torque)``).

While a batch runs, the BLAS library under NumPy and SciPy is limited to one
thread (:mod:`threadpoolctl`): the runs' small matrices (linearisations,
Riccati equations, matrix exponentials) gain nothing from BLAS threads, which
would only compete with the runs for the cores. The limit is process-wide and
lasts until the batch ends (for :func:`iter_simulations`, until the generator is
exhausted or closed).

A batch that ends early (the first error with ``errors="raise"``, the caller
closing the generator, ``KeyboardInterrupt``) stops the runs in flight at their
next chunk (:func:`flexarm.simulate`'s ``stop``) and starts no other.

Seeds: give each run its own seed (an int ``rng``), not a shared
:class:`numpy.random.Generator` (runs in threads would draw from it in an order
that depends on timing).
"""

from __future__ import annotations

import os
import sys
import threading
from collections.abc import Callable, Iterable, Iterator, Mapping
from concurrent.futures import FIRST_COMPLETED, Future, ThreadPoolExecutor, wait

from .._validation import check_int, check_option
from ..errors import InvalidTypeError
from .closed_loop import simulate
from .results import SimulationResult

__all__ = ["Outcome", "Run", "default_workers", "iter_simulations", "simulate_many"]

Run = Mapping[str, object] | Callable[[], SimulationResult]
"""One run: :func:`flexarm.simulate`'s arguments by name, or a callable."""

Outcome = SimulationResult | Exception
"""What a run gives: its result, or (with ``errors="return"``) the exception it
raised (:class:`~flexarm.sim.results.SimulationError` for a run that diverged,
with the partial result attached; ``ValueError`` for a bad combination of
parameters)."""

_OWNER = "simulate_many"


def default_workers() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _callable(run: Run, index: int, stop: threading.Event) -> Callable[[], SimulationResult]:
    if isinstance(run, Mapping):
        kwargs = {"stop": stop, **run}
        if "arm" not in kwargs:
            raise InvalidTypeError(
                f"The 'runs' parameter of {_OWNER} must hold mappings with an 'arm' (the "
                f"arguments of simulate) or callables. Run {index} has no 'arm'."
            )
        arm = kwargs.pop("arm")
        return lambda: simulate(arm, **kwargs)  # type: ignore[arg-type]
    if callable(run):
        return run
    raise InvalidTypeError(
        f"The 'runs' parameter of {_OWNER} must hold mappings of simulate's arguments or "
        f"callables. Run {index} is a {type(run).__name__}."
    )


def iter_simulations(
    runs: Iterable[Run],
    *,
    workers: int | None = None,
    errors: str = "return",
    progress: bool | None = None,
) -> Iterator[tuple[int, Outcome]]:
    """Run simulations on ``workers`` threads; yield ``(index, outcome)`` as each ends.

    Parameters
    ----------
    runs : iterable of mapping or callable
        The runs (module docstring), consumed lazily: at most ``2 * workers`` are
        prepared or running at any time.
    workers : int, optional
        Threads (default: every core this process may use, :func:`default_workers`).
    errors : {"return", "raise"}
        ``"return"``: a run that raises gives its exception as its outcome and the
        others go on; ``"raise"``: the first exception stops the batch (the runs in
        flight finish, none is started) and is raised.
    progress : bool, optional
        A progress bar on stderr (default: when stderr is a terminal and there is
        more than one run).

    Yields
    ------
    index : int
        The run's position in ``runs``.
    outcome : SimulationResult or Exception
    """
    n_workers = (
        default_workers() if workers is None else check_int(workers, "workers", _OWNER, minimum=1)
    )
    check_option(errors, "errors", _OWNER, ("return", "raise"))
    total = len(runs) if hasattr(runs, "__len__") else None  # type: ignore[arg-type]
    show = (sys.stderr.isatty() and total != 1) if progress is None else bool(progress)
    source = iter(enumerate(runs))
    pending: dict[Future[SimulationResult], int] = {}
    done_count = 0
    from threadpoolctl import threadpool_limits

    stop = threading.Event()  # set when the batch ends early: runs in flight stop

    with (
        threadpool_limits(limits=1, user_api="blas"),
        ThreadPoolExecutor(max_workers=n_workers, thread_name_prefix="flexarm-run") as pool,
    ):
        try:
            while True:
                while len(pending) < 2 * n_workers:
                    item = next(source, None)
                    if item is None:
                        break
                    index, run = item
                    pending[pool.submit(_callable(run, index, stop))] = index
                if not pending:
                    break
                finished, _ = wait(pending, return_when=FIRST_COMPLETED)
                for future in sorted(finished, key=pending.__getitem__):  # runs in order
                    index = pending.pop(future)
                    exc = future.exception()
                    done_count += 1
                    if show:
                        _progress(done_count, total)
                    if exc is not None:
                        if errors == "raise" or not isinstance(exc, Exception):
                            raise exc  # the runs in flight finish; none is started
                        yield index, exc
                    else:
                        yield index, future.result()
        finally:
            stop.set()  # the batch is over: whatever still runs stops at its next chunk
            for future in pending:
                future.cancel()
            if show:
                sys.stderr.write("\n")


def simulate_many(
    runs: Iterable[Run],
    *,
    workers: int | None = None,
    errors: str = "raise",
    progress: bool | None = None,
) -> list[Outcome]:
    """Run many simulations on every core; return their outcomes in order.

    Parameters
    ----------
    runs : iterable of mapping or callable
        Each a mapping of :func:`flexarm.simulate`'s arguments by name (``"arm"``
        required) or a callable with no arguments returning a
        :class:`~flexarm.sim.results.SimulationResult`.
    workers : int, optional
        Threads (default: every core this process may use).
    errors : {"raise", "return"}
        ``"raise"`` (default): the first run that raises stops the batch and its
        exception is raised. ``"return"``: that run's outcome is its exception
        (:class:`~flexarm.sim.results.SimulationError` carries the partial result)
        and the batch goes on.
    progress : bool, optional
        A progress bar on stderr (default: on a terminal, for more than one run).

    Returns
    -------
    list of SimulationResult or Exception
        One per run, in the order of ``runs``; each result bit for bit the one
        :func:`flexarm.simulate` gives for that run alone.

    Examples
    --------
    >>> import flexarm
    >>> from flexarm.sensing.sensors import JointSensor
    >>> arm = flexarm.FlexibleArm.paper()
    >>> runs = [{"arm": arm, "duration": 0.05, "rng": seed,
    ...          "sensor": JointSensor(noise_std=1e-4)} for seed in range(4)]
    >>> results = flexarm.simulate_many(runs, workers=2)
    >>> len(results), results[0].info["status"]
    (4, 'ok')
    """
    outcomes: dict[int, Outcome] = {}
    for index, outcome in iter_simulations(runs, workers=workers, errors=errors, progress=progress):
        outcomes[index] = outcome
    return [outcomes[i] for i in range(len(outcomes))]


def _progress(done: int, total: int | None) -> None:
    if total:
        width = 40
        filled = round(width * done / total)
        bar = f"[{'#' * filled}{'.' * (width - filled)}] {done}/{total}"
    else:
        bar = f"{done} done"
    sys.stderr.write(f"\rruns {bar}")
    sys.stderr.flush()
