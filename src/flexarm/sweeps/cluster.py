"""Doing a sweep's runs on a Dask cluster (``dask.distributed``): more than one machine.

:func:`iter_cluster_records` cuts the runs into chunks and submits one task per
chunk, :func:`~flexarm.sweeps.execute.run_chunk`, to the cluster's workers. A
chunk travels as plain data (run ids and scenario mappings: flexarm objects
hold compiled functions, which may not pickle); each worker builds and runs its
chunk with the batched simulator of its own flexarm and sends back the metric
records only. Seeds travel inside the scenarios, so a run's numbers do not
depend on which worker does it or when: the table equals the local one bit for
bit (on machines with the same CPU architecture and library builds).

Install: ``pip install 'flexarm[dask]'`` (``dask[distributed]`` and pyarrow) on the
machine that submits and on every worker, with the same flexarm version.

Running on a cluster (SLURM here; PBS, SGE, LSF, Kubernetes alike)::

    # on the login node
    from dask_jobqueue import SLURMCluster
    from dask.distributed import Client
    import flexarm

    cluster = SLURMCluster(
        cores=32, processes=32, memory="64GB", walltime="02:00:00",
        job_script_prologue=[
            "export NUMBA_CACHE_DIR=/tmp/$USER/numba",   # node-local
            "export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1",
        ],
    )
    cluster.scale(jobs=4)                                 # 4 nodes, 128 workers
    table = flexarm.sweep("sweep.toml", out="results", client=Client(cluster))

or start a scheduler and workers yourself (``dask scheduler``, ``dask worker
tcp://host:8786 --nworkers 32 --nthreads 1``) and run
``flexarm sweep sweep.toml --scheduler tcp://host:8786``.

Pitfalls
--------
* **Each worker compiles flexarm's Numba functions** the first time it runs a
  simulation (tens of seconds), or loads them from its Numba cache. Set
  ``NUMBA_CACHE_DIR`` to a node-local directory on each node (a cache on a
  shared file system is written by many processes at once and is slow), and
  warm it once per node (e.g. ``flexarm simulate --duration 0.01`` in the job
  prologue) so that the workers load instead of compiling.
* **Processes, not threads**: a run's compiled loop releases the GIL, but its
  set-up (building the scenario, the reference, the metrics) is Python and holds
  it. Give each worker one thread and start one worker process per core
  (``--nworkers N --nthreads 1``, ``processes=N`` with ``cores=N``), and keep
  BLAS to one thread per process (``OPENBLAS_NUM_THREADS=1``).
* **Seeds travel with the runs**: a noisy sensor needs ``simulation.seed`` in the
  scenario (swept or in the base); a run without one draws fresh noise and is
  not reproducible.
* **Chunks**: a task per run costs the scheduler more than a short run takes;
  by default a sweep is cut into about four chunks per worker thread
  (``chunk_size`` sets it). A chunk lost with its worker is run again by Dask;
  an interrupted sweep resumes from its journal like a local one.
"""

from __future__ import annotations

import socket
from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

from ..errors import ClusterError, InvalidValueError
from .execute import Item, default_chunk_size, run_chunk
from .records import Record

if TYPE_CHECKING:
    from distributed import Client

__all__ = [
    "DASK_EXTRA",
    "ClusterError",
    "connect",
    "have_distributed",
    "iter_cluster_records",
]

DASK_EXTRA = "pip install 'flexarm[dask]'"
"""What installs dask.distributed (and pyarrow)."""


def have_distributed() -> bool:
    """Whether ``dask.distributed`` can be imported."""
    try:
        import distributed  # noqa: F401
    except ImportError:
        return False
    return True


def connect(address: str, timeout: float = 10.0) -> Client:
    """A client of the Dask scheduler at ``address`` (``tcp://host:8786``).

    Raises
    ------
    InvalidValueError
        If dask.distributed is not installed (the message says how to install it)
        or the scheduler cannot be reached within ``timeout`` s.
    """
    if not have_distributed():
        raise InvalidValueError(f"a Dask scheduler needs dask.distributed: {DASK_EXTRA}")
    from distributed import Client
    from distributed.comm.addressing import parse_address, parse_host_port

    try:
        scheme, location = parse_address(address)
        if scheme == "tcp":  # fail fast, before a Client that would linger on failure
            host, port = parse_host_port(location, default_port=8786)
            socket.create_connection((host, port), timeout=timeout).close()
        return Client(address, timeout=timeout)
    except (OSError, TimeoutError, ValueError, TypeError) as exc:
        text = " ".join(str(exc).split()) or type(exc).__name__
        raise InvalidValueError(
            f"cannot connect to the Dask scheduler at {address!r}: {text}"
        ) from None


def iter_cluster_records(
    items: Sequence[Item],
    client: Client,
    *,
    chunk_size: int | None = None,
    workers: int = 1,
) -> Iterator[Record]:
    """Do the runs ``items`` on the cluster of ``client``; yield records as chunks finish.

    Parameters
    ----------
    items : sequence of (str, mapping)
        Run ids and scenario mappings.
    client : distributed.Client
        A client of the cluster.
    chunk_size : int, optional
        Runs per task (default: :func:`default_chunk_size` over the cluster's
        worker threads).
    workers : int
        Threads each task uses on its worker (default 1: one run at a time per
        worker thread).

    Raises
    ------
    ClusterError
        If a task fails (the records yielded before are good).
    """
    from distributed import as_completed

    threads = sum(client.nthreads().values())
    size = chunk_size or default_chunk_size(len(items), threads)
    futures = [
        client.submit(run_chunk, list(items[i : i + size]), workers, pure=False)
        for i in range(0, len(items), size)
    ]
    try:
        for future in as_completed(futures):
            try:
                records = future.result()
            except Exception as exc:
                text = " ".join(str(exc).split())
                raise ClusterError(f"a Dask task failed: {type(exc).__name__}: {text}") from exc
            yield from records
    finally:
        client.cancel([f for f in futures if not f.done()])
