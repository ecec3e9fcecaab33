"""Section ``dynamics``: what one forward-dynamics evaluation costs, per backend and n.

Every backend of `gimwatch.simulation.backends.BACKENDS` (``aba``, ``crba-cholesky``,
``denoc``, and any registered later) is built for the paper's chain of n rods under
gravity (−y) and its ``forward_dynamics(q, v, τ)`` — one right-hand-side evaluation of a
simulation step; RK4 makes 4 per step, DOP853 12 — is timed at one seeded random state
(median per call, `gimwatch.bench.timing.time_call`). Ratios are to ``aba`` in the
same run.

Above nv = 400 the Pinocchio backends would refuse to build their Data (it grows as nv³);
the benchmark hands them one from `gimwatch.bench.timing.data_if_it_fits` when it
fits in half the available memory (else the row is left empty and says why) and frees it
before the next backend.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from functools import partial
from typing import cast

import numpy as np

from gimwatch.bench import BenchContext, SectionResult
from gimwatch.bench.compare import Case, Comparison, run_comparison
from gimwatch.bench.plots import plot_dynamics_cost
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import data_if_it_fits
from gimwatch.errors import RobotError
from gimwatch.model.robots import DATA_NV_LIMIT, Robot, load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.backends import BACKENDS

__all__ = ["COLUMNS", "COMPARISON", "FULL_SIZES", "QUICK_SIZES", "run"]

FULL_SIZES = (10, 100, 500)
QUICK_SIZES = (4,)
GRAVITY = np.array([0.0, -9.81, 0.0])
COLUMNS = ("n", "backend", "call_us", "min_us", "calls_per_round", "vs_aba", "note")


class _LargeRobot:
    """A robot whose ``new_data()`` returns a Data built past the library's nv limit."""

    def __init__(self, robot: Robot, data) -> None:
        self._robot, self._data = robot, data

    def __getattr__(self, name: str):
        return getattr(self._robot, name)

    def new_data(self):
        return self._data


def _backend(name: str, robot: Robot):
    """The backend, or (None, why) when its Pinocchio Data would not fit."""
    cls = BACKENDS[name]  # not make_backend: it swaps in denoc above DATA_NV_LIMIT
    try:
        return cls(robot, GRAVITY), ""
    except RobotError as exc:  # new_data() refuses nv > DATA_NV_LIMIT
        if robot.nv <= DATA_NV_LIMIT:
            raise
        data = data_if_it_fits(robot)
        if data is None:
            return None, f"not timed: a Pinocchio Data for nv = {robot.nv} would not fit ({exc})"
        return cls(cast(Robot, _LargeRobot(robot, data)), GRAVITY), (
            f"Data built past nv = {DATA_NV_LIMIT} for this benchmark"
        )


def _calls(facts: dict, robot: Robot) -> Iterator[tuple[str, Callable[[], object] | None]]:
    """Each backend's forward dynamics at the state in ``facts``, built when it is timed."""
    q, v, tau = facts["state"]
    for name in BACKENDS:
        backend, facts[f"note:{name}"] = _backend(name, robot)
        yield name, (None if backend is None else partial(backend.forward_dynamics, q, v, tau))
        del backend  # its Data before the next backend's (gigabytes past nv = 400)


def _case(n: int, context: BenchContext) -> Case:
    robot = load_robot(f"chain:{n}")
    rng = np.random.default_rng(context.seed)
    q = random_configurations(robot, 1, seed=context.seed)[0]
    facts = {"n": n, "state": (q, *rng.standard_normal((2, robot.nv)))}  # q, v, τ
    return Case(f"chain:{n}", _calls(facts, robot), facts)


def _rows(case: Case) -> Iterator[dict]:
    aba = case.timings["aba"]
    for name, timing in case.timings.items():
        yield {
            "n": case.facts["n"],
            "backend": name,
            "call_us": np.nan if timing is None else timing.median_s * 1e6,
            "min_us": np.nan if timing is None else timing.min_s * 1e6,
            "calls_per_round": 0 if timing is None else timing.number,
            "vs_aba": timing.median_s / aba.median_s if timing and aba else np.nan,
            "note": case.facts[f"note:{name}"],
        }


#: Every registered backend's forward dynamics, per chain size, against ``aba``.
COMPARISON = Comparison("dynamics", COLUMNS, FULL_SIZES, QUICK_SIZES, _case, _rows)


def run(context: BenchContext) -> SectionResult:
    """Measure, plot ``dynamics_cost.png`` and tabulate the ratios to ``aba``."""
    table = run_comparison(COMPARISON, context)
    figure = plot_dynamics_cost(table.rows, context.output / "dynamics_cost.png")
    columns = {
        "n": "n",
        "backend": "backend",
        "call_us": "FD call (µs)",
        "vs_aba": "/ aba",
        "note": "note",
    }
    text = [
        "One forward-dynamics evaluation q̈ = FD(q, v, τ) of the paper's chain under gravity "
        "(a simulation's right-hand side: RK4 makes 4 per step, DOP853 12), median µs per "
        "call at one seeded random state; `/ aba` is the ratio to Pinocchio's ABA in the "
        "same run. `crba-cholesky` forms M (O(n²)) and factors it (O(n³)); `denoc` is "
        "gimwatch's DeNOC forward dynamics (compiled O(n) recursions for fixed-base chains, "
        "no Pinocchio).",
        "",
        markdown_table(table.rows, columns),
    ]
    ratios = {f"{r['backend']}@{r['n']}": r["vs_aba"] for r in table.rows if r["backend"] != "aba"}
    return SectionResult(
        name="dynamics",
        title="Dynamics backends per step",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(text),
        summary={"vs_aba": ratios},
    )
