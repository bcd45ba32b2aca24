"""Independent jobs (sequence x tracker, run x processor) on local worker processes or a Dask cluster.

``run_jobs(score, jobs)`` is the one executor ``uav-tui eval`` and ``uav-tui replay`` share. Locally it
uses a spawn-started process pool (the same on a Pi and in CI); with ``cluster="tcp://HOST:8786"`` the
same calls go to an existing Dask distributed scheduler, whose workers must be able to import the
job function (install uav-tui on them). Results come back in job order whichever way they ran.
"""

from __future__ import annotations

import multiprocessing
import os
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from typing import Any, TypeVar

from uav_tui.errors import ConfigError

J = TypeVar("J")
R = TypeVar("R")

Progress = Callable[[int, int], None]
"""Called as ``progress(done, total)`` each time a job finishes."""
OnResult = Callable[[int, Any], None]
"""Called as ``on_result(index, result)`` each time a job finishes (``index`` in ``jobs``), before ``progress``."""


def default_workers() -> int:
    """One worker per core this process may use."""
    return max(1, len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1)


def run_jobs(function: Callable[[J], R], jobs: Sequence[J], *, workers: int | None = None,
             cluster: str | None = None, progress: Progress | None = None,
             on_result: OnResult | None = None) -> list[R]:
    """Call ``function(job)`` for every job and return the results in the order of ``jobs``.

    Args:
        function: a module-level function (it is sent to other processes by reference).
        jobs: picklable job descriptions.
        workers: local worker processes (default: one per core); 1 runs in this process.
        cluster: a Dask scheduler address; when given, ``workers`` is ignored.
        progress: told after each finished job.
        on_result: given each result as its job finishes (to keep what is done if the rest never finishes).

    Raises:
        ConfigError: ``cluster`` is given but Dask distributed is not installed or not reachable.
        Whatever ``function`` raised, for the first job that failed.
    """
    if cluster:
        return _run_on_dask(function, jobs, cluster, progress, on_result)
    count = min(workers or default_workers(), len(jobs))
    if count <= 1:
        results = []
        for job in jobs:
            results.append(function(job))
            if on_result:
                on_result(len(results) - 1, results[-1])
            if progress:
                progress(len(results), len(jobs))
        return results
    results_by_index: dict[int, R] = {}
    with ProcessPoolExecutor(count, mp_context=multiprocessing.get_context("spawn")) as pool:
        futures = {pool.submit(function, job): index for index, job in enumerate(jobs)}
        try:
            for future in as_completed(futures):
                results_by_index[futures[future]] = future.result()
                if on_result:
                    on_result(futures[future], results_by_index[futures[future]])
                if progress:
                    progress(len(results_by_index), len(jobs))
        except BaseException:
            pool.shutdown(wait=False, cancel_futures=True)  # jobs not started yet never start
            raise
    return [results_by_index[index] for index in range(len(jobs))]


def _run_on_dask(function: Callable[[Any], R], jobs: Sequence[Any], address: str,
                 progress: Progress | None, on_result: OnResult | None) -> list[R]:
    try:
        from distributed import Client
        from distributed import as_completed as dask_completed
    except ImportError:
        raise ConfigError("--cluster needs Dask distributed: pip install 'uav-tui[cluster]' "
                          "(and the same on every worker)", key="cluster") from None
    try:
        client = Client(address, timeout="10s", set_as_default=False)
    except (OSError, TimeoutError) as exc:
        raise ConfigError(f"--cluster {address}: cannot reach the Dask scheduler ({exc}); is "
                          "`dask scheduler` running there?", key="cluster") from None
    with client:
        futures = client.map(function, list(jobs), pure=False)
        index_of = {future.key: index for index, future in enumerate(futures)}
        results_by_index: dict[int, R] = {}
        for future in dask_completed(futures, loop=client.loop):  # the client is not the default one
            results_by_index[index_of[future.key]] = future.result()
            if on_result:
                on_result(index_of[future.key], results_by_index[index_of[future.key]])
            if progress:
                progress(len(results_by_index), len(jobs))
    return [results_by_index[index] for index in range(len(jobs))]
