"""Run independent chunks of work in-process, on local processes, or on a Dask cluster.

A sweep is a list of `Task` (a picklable module-level function and its arguments).
Results come back keyed by the task's position, so their order never depends on which worker
finished first: the same tasks give the same results on any backend.

Backends:

* ``workers=1`` — in this process, one task after another (notebooks, tests, debugging);
* ``workers=N`` — a `concurrent.futures.ProcessPoolExecutor`;
* ``workers=None`` (default) — every core, unless every task states its cost and they add up
  to less than `POOL_WORTH_S`: starting worker processes (each imports gimwatch,
  Pinocchio and SciPy) costs seconds, more than tiny sweeps take in this process;
* ``scheduler="local"`` — a fresh Dask ``LocalCluster`` (one single-threaded worker per core);
* ``scheduler="tcp://host:port"`` — an existing Dask scheduler.

Every task runs with BLAS limited to one thread (`run_task`): GIMs are small dense
matrices, for which multi-threaded OpenBLAS is 20-40x slower on 2 cores, and workers already
use the cores in parallel. Ctrl-C (`KeyboardInterrupt`) stops the sweep and returns what
was finished; pending tasks are cancelled.
"""

from __future__ import annotations

import os
import signal
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

from gimwatch.errors import InputError
from gimwatch.survey.scheduler_address import probe_scheduler

__all__ = ["POOL_WORTH_S", "SweepOutcome", "Task", "run_sweep", "run_task"]

#: Estimated in-process seconds below which a sweep runs in this process by default: a pool
#: of spawned workers took 3-8 s to start on a 2-core machine (2 robots x 20 samples: 8-10 s
#: in a pool for 0.2 s of work).
POOL_WORTH_S = 5.0


@dataclass(frozen=True)
class Task:
    """One unit of work: ``function(*args)``; ``function`` must be importable by name.

    ``cost_s`` is an estimate of its in-process time in seconds (None: unknown), used only to
    decide whether a default sweep is worth a process pool.
    """

    function: Callable[..., Any]
    args: tuple = ()
    cost_s: float | None = None


@dataclass(frozen=True)
class SweepOutcome:
    """What a sweep finished.

    Attributes:
        results: Task position -> its return value, for the tasks that finished.
        interrupted: True when Ctrl-C stopped the sweep before every task finished.
    """

    results: dict[int, Any] = field(default_factory=dict)
    interrupted: bool = False


def run_task(function: Callable[..., Any], *args: Any) -> Any:
    """Call ``function(*args)`` with BLAS on one thread (small matrices, parallel workers)."""
    from threadpoolctl import threadpool_limits

    with threadpool_limits(limits=1, user_api="blas"):
        return function(*args)


def _default_workers(tasks: Sequence[Task]) -> int:
    known = [task.cost_s for task in tasks if task.cost_s is not None]
    if len(known) == len(tasks) and sum(known) < POOL_WORTH_S:
        return 1
    return os.cpu_count() or 1


def _ignore_sigint() -> None:  # worker processes: Ctrl-C is the parent's business
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _run_serial(tasks, done, results) -> None:
    for index, task in enumerate(tasks):
        results[index] = run_task(task.function, *task.args)
        done(index)


def _run_processes(tasks, workers, done, results) -> None:
    import multiprocessing
    from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait

    # spawn, not fork: the parent may hold threads (progress bar, BLAS pools)
    context = multiprocessing.get_context("spawn")
    pool = ProcessPoolExecutor(
        max_workers=min(workers, len(tasks)), mp_context=context, initializer=_ignore_sigint
    )
    try:
        futures = {pool.submit(run_task, t.function, *t.args): i for i, t in enumerate(tasks)}
        pending = set(futures)
        while pending:
            finished, pending = wait(pending, return_when=FIRST_COMPLETED)
            for future in sorted(finished, key=futures.__getitem__):
                results[futures[future]] = future.result()
                done(futures[future])
    finally:
        pool.shutdown(wait=True, cancel_futures=True)


def _dask_client(scheduler: str):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise InputError(
            "scheduler",
            "usable only with Dask installed",
            scheduler,
            hint="pip install 'gimwatch[dask]'",
        ) from None
    if scheduler == "local":
        cluster = LocalCluster(
            n_workers=os.cpu_count() or 1, threads_per_worker=1, dashboard_address=None
        )
        return Client(cluster), cluster
    # a malformed address, a silent port or an HTTP server fail now, in one line
    probe_scheduler(scheduler)
    try:
        return Client(scheduler, timeout="10s"), None
    except (OSError, TimeoutError, ValueError) as exc:
        raise InputError(
            "scheduler", "the address of a running Dask scheduler or 'local'", scheduler
        ) from exc


def _run_dask(tasks, scheduler, done, results) -> None:
    from distributed import as_completed

    client, cluster = _dask_client(scheduler)
    futures = []
    try:
        futures = [
            client.submit(run_task, t.function, *t.args, pure=False, key=f"gimwatch-task-{i}")
            for i, t in enumerate(tasks)
        ]
        position = {future.key: i for i, future in enumerate(futures)}
        for future in as_completed(futures):
            results[position[future.key]] = future.result()
            done(position[future.key])
    finally:
        client.cancel(futures)
        client.close()
        if cluster is not None:
            cluster.close()


def run_sweep(
    tasks: Sequence[Task],
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    progress: Callable[[int], None] | None = None,
) -> SweepOutcome:
    """Run ``tasks`` and return their results by position; Ctrl-C returns the finished part.

    Args:
        tasks: The work; each function must be importable (it is pickled by name).
        workers: Local processes; 1 runs in this process. Default: this process when every
            task states a cost and they sum to less than `POOL_WORTH_S`, else
            ``os.cpu_count()`` processes. Ignored when ``scheduler`` is given.
        scheduler: ``"local"`` for a fresh Dask ``LocalCluster``, or the address of a
            running Dask scheduler; None for local processes.
        progress: Called with the position of each finished task, in completion order.

    Raises:
        InputError: ``workers`` < 1, or the scheduler cannot be reached.
    """
    if workers is not None and (isinstance(workers, bool) or workers < 1):
        raise InputError("workers", "a positive integer", workers)
    tasks = list(tasks)
    results: dict[int, Any] = {}

    def done(index: int) -> None:
        if progress is not None:
            progress(index)

    try:
        if not tasks:
            pass
        elif scheduler is not None:
            _run_dask(tasks, scheduler, done, results)
        elif (workers or _default_workers(tasks)) == 1:
            _run_serial(tasks, done, results)
        else:
            _run_processes(tasks, workers or _default_workers(tasks), done, results)
    except KeyboardInterrupt:
        return SweepOutcome(results=results, interrupted=True)
    return SweepOutcome(results=results, interrupted=False)
