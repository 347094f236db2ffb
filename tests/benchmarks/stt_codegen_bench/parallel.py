"""Run independent jobs in parallel: local processes, or an existing Dask cluster.

Local runs use :class:`concurrent.futures.ProcessPoolExecutor` with the ``spawn`` start
method (each worker is a fresh interpreter: no state forked from the parent, and no
OpenMP or thread state shared). ``--scheduler ADDRESS`` submits the same jobs to a running
``dask.distributed`` scheduler through a :class:`distributed.Client`; the workers must
have ``stt-codegen`` installed (with the ``bench`` extra). Progress is a :mod:`tqdm` bar
on standard error. Results are returned in submission order.
"""

from __future__ import annotations

import multiprocessing
import os
import sys
from collections.abc import Callable, Sequence
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures import as_completed as local_as_completed
from typing import Any

from tqdm import tqdm

from stt_codegen.errors import SpecError

__all__ = ["run_parallel"]

#: How long to wait for a Dask scheduler to answer.
CONNECT_TIMEOUT = "10s"


def default_workers() -> int:
    """The number of local worker processes by default: the CPUs this process may use."""
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


def run_parallel(fn: Callable[..., Any], calls: Sequence[tuple], workers: int | None = None,
                 scheduler: str | None = None, progress: bool = True,
                 description: str = "") -> list[Any]:
    """``[fn(*args) for args in calls]``, computed in parallel.

    Parameters
    ----------
    fn : callable
        A picklable top-level function.
    calls : sequence of tuple
        Positional arguments of each call.
    workers : int, optional
        Local worker processes (default :func:`default_workers`); ignored with
        ``scheduler``.
    scheduler : str, optional
        Address of a Dask scheduler (e.g. ``tcp://127.0.0.1:8786``).
    progress : bool
        Show a tqdm progress bar on standard error.
    description : str
        Label of the progress bar.

    Returns
    -------
    list
        Results, in the order of ``calls``.

    Raises
    ------
    SpecError
        ``workers < 1`` (field ``workers``), or the scheduler cannot be reached
        (field ``scheduler``).
    Exception
        Whatever a job raised (the first one, re-raised here).
    """
    results: list[Any] = [None] * len(calls)
    if scheduler:
        client = _connect(scheduler)
        try:
            with _bar(len(calls), description, progress) as bar:
                _run_dask(client, fn, calls, results, bar)
        finally:
            client.close()
        return results
    workers = default_workers() if workers is None else workers
    if workers < 1:
        raise SpecError("workers", f"must be at least 1, got {workers}")
    context = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(max_workers=min(workers, max(1, len(calls))),
                             mp_context=context) as pool, \
            _bar(len(calls), description, progress) as bar:
        futures = {pool.submit(fn, *args): k for k, args in enumerate(calls)}
        for future in local_as_completed(futures):
            results[futures[future]] = future.result()
            bar.update(1)
    return results


def _bar(total: int, description: str, progress: bool) -> tqdm:
    return tqdm(total=total, desc=description, file=sys.stderr, disable=not progress,
                unit="job")


def _connect(scheduler: str):
    from distributed import Client
    try:
        return Client(scheduler, timeout=CONNECT_TIMEOUT)
    except (OSError, TimeoutError, ValueError) as exc:
        raise SpecError("scheduler", f"cannot connect to {scheduler!r}: {exc}") from None


def _run_dask(client, fn, calls, results: list, bar) -> None:
    from distributed import as_completed as dask_as_completed
    futures = [client.submit(fn, *args, pure=False) for args in calls]
    index = {f.key: k for k, f in enumerate(futures)}
    for future in dask_as_completed(futures):
        results[index[future.key]] = future.result()
        bar.update(1)
