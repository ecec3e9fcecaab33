"""Timing for the benchmarks: warm-up, repeats, medians; BLAS thread settings.

Every cost in ``gimwatch bench`` comes from `time_call`: the call is warmed up, then
timed in ``repeats`` rounds of ``number`` calls each (``number`` chosen so a round lasts at
least ``min_round_s``, as `timeit`'s autorange does), and the median of the per-call
times is kept. Ratios are always taken between medians measured in the same run.
"""

from __future__ import annotations

import os
import statistics
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.linalg
from threadpoolctl import threadpool_info, threadpool_limits

from gimwatch.model.robots import DATA_NV_LIMIT, Robot

__all__ = [
    "Timing",
    "blas_thread_ratio",
    "data_if_it_fits",
    "thread_settings",
    "time_call",
]


@dataclass(frozen=True)
class Timing:
    """The measured cost of one call.

    Attributes:
        median_s: Median seconds per call over the rounds.
        min_s: Fastest round, seconds per call.
        rounds: Number of timed rounds.
        number: Calls per round.
    """

    median_s: float
    min_s: float
    rounds: int
    number: int


def time_call(
    fn: Callable[[], object],
    *,
    warmup: int = 2,
    repeats: int = 7,
    min_round_s: float = 0.02,
    max_number: int = 100_000,
) -> Timing:
    """Median time of ``fn()`` after ``warmup`` calls, over ``repeats`` rounds.

    Args:
        fn: The call to time (no arguments; bind them with a closure or ``functools.partial``).
        warmup: Untimed calls first (caches, lazy imports, allocation).
        repeats: Timed rounds; the median per-call time of the rounds is reported.
        min_round_s: Each round repeats ``fn`` until it lasts at least this long.
        max_number: Upper bound on calls per round.
    """
    for _ in range(warmup):
        fn()
    number = 1
    while True:  # autorange: grow the round until it is long enough to time
        start = time.perf_counter()
        for _ in range(number):
            fn()
        elapsed = time.perf_counter() - start
        if elapsed >= min_round_s or number >= max_number:
            break
        number = min(max_number, number * (2 if elapsed > min_round_s / 10 else 10))
    per_call = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            fn()
        per_call.append((time.perf_counter() - start) / number)
    return Timing(
        median_s=float(statistics.median(per_call)),
        min_s=float(min(per_call)),
        rounds=repeats,
        number=number,
    )


def thread_settings() -> str:
    """The BLAS/OpenMP thread pools as threadpoolctl sees them now, e.g. ``openblas: 1``."""
    pools = [f"{p['internal_api']}: {p['num_threads']}" for p in threadpool_info()]
    return ", ".join(pools) if pools else "no BLAS thread pool found"


def blas_thread_ratio(n: int = 100, *, seed: int = 0, quick: bool = False) -> dict[str, float]:
    """Time a symmetric n x n ``eigvalsh`` with BLAS on one thread and on every core.

    Returns:
        ``{"n", "threads_all", "one_thread_s", "all_threads_s", "ratio"}`` with
        ``ratio = all_threads_s / one_thread_s`` (> 1: threads make it slower).
    """
    rng = np.random.default_rng(seed)
    A = rng.standard_normal((n, n))
    A = A @ A.T + n * np.eye(n)
    repeats, min_round = (3, 0.005) if quick else (7, 0.05)
    cores = os.cpu_count() or 1

    def solve() -> None:
        scipy.linalg.eigvalsh(A, check_finite=False)

    with threadpool_limits(limits=1, user_api="blas"):
        one = time_call(solve, repeats=repeats, min_round_s=min_round)
    with threadpool_limits(limits=cores, user_api="blas"):
        many = time_call(solve, repeats=repeats, min_round_s=min_round)
    return {
        "n": n,
        "threads_all": cores,
        "one_thread_s": one.median_s,
        "all_threads_s": many.median_s,
        "ratio": many.median_s / one.median_s,
    }


#: Bytes of a Pinocchio Data for a chain of nv bodies, fitted on nv = 100 … 300.
_DATA_BYTES_AT_300 = 1.25e9


def _available_bytes() -> float:
    try:
        with open("/proc/meminfo", encoding="utf-8") as handle:
            for line in handle:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return float("inf")


def data_if_it_fits(robot: Robot):
    """A Pinocchio Data for a benchmark, or None when it would not fit in memory.

    Data grows as nv³ (≈ 1.25 GB at nv = 300). Up to ``DATA_NV_LIMIT`` this is
    ``robot.new_data()``; above, a Data is built (deliberately past the library's limit)
    only when its estimated size is below half the available memory. The caller frees it
    before the next size.
    """
    if robot.nv <= DATA_NV_LIMIT:
        return robot.new_data()
    needed = _DATA_BYTES_AT_300 * (robot.nv / 300) ** 3
    if needed > 0.5 * _available_bytes():
        return None
    return robot.model.createData()
