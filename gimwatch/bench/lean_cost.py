"""Section ``lean``: what one δ sample costs, against Pinocchio's ABA and against κ by eig.

For the paper's chain of n rods (one seeded set of random configurations per n), side by side
in one run, median µs per call (`gimwatch.bench.timing.time_call`, BLAS on one thread —
the CLI pins it with threadpoolctl):

* ``delta_watch_us`` — one
  [`sample`][gimwatch.watch.watch.Watch.sample] watching δ only, the watch built as a user
  builds it (``Watch(robot, ("diagonal_ratio",))``, docs/watch.md): it takes diag M from
  DeNOC's compiled [`LeanModel`][gimwatch.denoc.LeanModel] (one call, buffers preallocated)
  and checks q;
* ``delta_lean_us`` — δ alone from ``LeanModel.diagonal_ratio`` (one compiled call);
* ``delta_pinocchio_us`` — the Pinocchio route: ``computeCentroidalMap`` + the column dot
  products of [`gim_diagonal`][gimwatch.model.inertia.gim_diagonal], then δ;
* ``aba_call_us`` — one ``pinocchio.aba`` call; ``rk4_step_us`` — a bare RK4 step (4 ABA
  calls and the stage arithmetic, nothing else);
* ``kappa_eig_us`` — κ by CRBA + ``eigvalsh``.

Ratios: the watch's δ sample against one ABA call and against the bare RK4 step (its cost if
it sampled every step), and κ-eig / δ-O(n) (the lean call: δ by the O(n) route itself).
Pinocchio's Data grows as nv³: above ``DATA_NV_LIMIT`` it is built deliberately, only when
it fits in half the available memory (`gimwatch.bench.timing.data_if_it_fits`), and
freed before the next size.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pinocchio as pin
import scipy.linalg
from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult
from gimwatch.bench.compare import Case, Comparison, run_comparison
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import data_if_it_fits
from gimwatch.metrics.conditioning import diagonal_ratio
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.backends import DenocBackend
from gimwatch.watch.watch import Watch

__all__ = ["COLUMNS", "COMPARISON", "FULL_SIZES", "QUICK_SIZES", "TARGETS", "run"]

FULL_SIZES = (20, 100, 200, 500)
QUICK_SIZES = (4, 8)
DT_S = 1e-3
GRAVITY = np.array([0.0, -9.81, 0.0])
#: Issue 16's targets: δ sample / ABA call and / RK4 step at n = 20; κ-eig / δ at 200, 500.
TARGETS: dict[str, Any] = {
    "aba_calls": 1.5,
    "step_share": 0.15,
    "kappa_eig_vs_delta": {200: 100, 500: 300},
}
COLUMNS = (
    "n",
    "delta_watch_us",
    "delta_lean_us",
    "delta_pinocchio_us",
    "aba_call_us",
    "rk4_step_us",
    "watch_vs_aba_call",
    "watch_vs_rk4_step",
    "kappa_eig_us",
    "kappa_eig_vs_delta",
    "note",
)


def _rk4_step(model, data, q, v, tau):
    """One bare RK4 step of q̈ = ABA(q, v, τ): 4 ABA calls and the stage arithmetic."""
    h = DT_S

    def step() -> None:
        a1 = pin.aba(model, data, q, v, tau)
        q2, v2 = q + 0.5 * h * v, v + 0.5 * h * a1
        a2 = pin.aba(model, data, q2, v2, tau)
        q3, v3 = q + 0.5 * h * v2, v + 0.5 * h * a2
        a3 = pin.aba(model, data, q3, v3, tau)
        q4, v4 = q + h * v3, v + h * a3
        a4 = pin.aba(model, data, q4, v4, tau)
        _ = q + h / 6 * (v + 2 * v2 + 2 * v3 + v4), v + h / 6 * (a1 + 2 * a2 + 2 * a3 + a4)

    return step


def _watch_sampler(watch: Watch, qs: np.ndarray):
    state = {"k": 0}

    def sample() -> None:
        k = state["k"] = state["k"] + 1
        watch.sample(k * DT_S, qs[k % len(qs)])

    return sample


def _pinocchio_calls(robot, data, q, v, tau) -> dict[str, Callable[[], object] | None]:
    """δ by the Pinocchio route, one ABA call, a bare RK4 step, κ by CRBA + eigvalsh."""
    if data is None:
        return dict.fromkeys(_PINOCCHIO)
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(GRAVITY, np.zeros(3))
    return {
        "delta_pinocchio_us": lambda: diagonal_ratio(gim_diagonal(robot, q, data=data)),
        "aba_call_us": lambda: pin.aba(model, data, q, v, tau),
        "rk4_step_us": _rk4_step(model, data, q, v, tau),
        "kappa_eig_us": lambda: scipy.linalg.eigvalsh(pin.crba(model, data, q), check_finite=False),
    }


_PINOCCHIO = ("delta_pinocchio_us", "aba_call_us", "rk4_step_us", "kappa_eig_us")


def _case(n: int, context: BenchContext) -> Case:
    robot = load_robot(f"chain:{n}")
    qs = random_configurations(robot, 16, seed=context.seed)
    rng = np.random.default_rng(context.seed)
    v, tau = rng.standard_normal((2, robot.nv))
    lean = DenocBackend(robot, GRAVITY).lean  # its LeanModel: no Pinocchio Data needed
    watch = Watch(robot, ("diagonal_ratio",))  # as a user builds it (docs/watch.md)
    q0 = qs[0]
    calls = {
        "delta_watch_us": _watch_sampler(watch, qs),
        "delta_lean_us": lambda: lean.diagonal_ratio(q0),
    }
    data = data_if_it_fits(robot)
    calls.update(_pinocchio_calls(robot, data, q0, v, tau))
    if data is None:
        note = "Pinocchio not timed: its Data would not fit in memory"
    else:
        note = "" if n <= 400 else "Pinocchio Data built past the library's limit"
    return Case(f"chain:{n}", calls, {"n": n, "note": note})


def _row(case: Case) -> list[dict]:
    us = {
        name: float("nan") if timing is None else timing.median_s * 1e6
        for name, timing in case.timings.items()
    }
    watch = us["delta_watch_us"]
    return [
        {
            "n": case.facts["n"],
            **us,
            "watch_vs_aba_call": watch / us["aba_call_us"],
            "watch_vs_rk4_step": watch / us["rk4_step_us"],
            "kappa_eig_vs_delta": us["kappa_eig_us"] / us["delta_lean_us"],
            "note": case.facts["note"],
        }
    ]


#: The δ routes against ABA, an RK4 step and κ by eig, one row per chain size.
COMPARISON = Comparison("lean", COLUMNS, FULL_SIZES, QUICK_SIZES, _case, _row)


def verdicts(rows: list[dict]) -> list[str]:
    """Issue 16's δ targets against the measured rows (one line each)."""
    by_n = {r["n"]: r for r in rows}
    lines = []
    if 20 in by_n:
        r = by_n[20]
        for key, column, what in (
            ("aba_calls", "watch_vs_aba_call", "Pinocchio `aba` calls"),
            ("step_share", "watch_vs_rk4_step", "of a bare RK4 + ABA step"),
        ):
            limit, got = TARGETS[key], r[column]
            verdict = "met" if got <= limit else "not met"
            lines.append(f"n = 20: δ sample = {got:.3g} {what} (target ≤ {limit:g}: {verdict})")
    for n, needed in TARGETS["kappa_eig_vs_delta"].items():
        if n in by_n and np.isfinite(by_n[n]["kappa_eig_vs_delta"]):
            got = by_n[n]["kappa_eig_vs_delta"]
            verdict = "met" if got >= needed else "not met"
            lines.append(f"n = {n}: κ-eig / δ-O(n) = {got:.0f}x (target ≥ {needed}x: {verdict})")
    return lines


def run(context: BenchContext) -> SectionResult:
    """Measure and summarise against the δ cost targets."""
    # BLAS on one thread, set here: the CLI's limit misses an OpenBLAS loaded after it
    with threadpool_limits(limits=1, user_api="blas"):
        table = run_comparison(COMPARISON, context)
    columns = {
        "n": "n",
        "delta_watch_us": "δ watch sample (µs)",
        "delta_lean_us": "δ lean call (µs)",
        "delta_pinocchio_us": "δ Pinocchio route (µs)",
        "aba_call_us": "aba call (µs)",
        "rk4_step_us": "bare RK4 step (µs)",
        "watch_vs_aba_call": "sample / aba",
        "watch_vs_rk4_step": "sample / step",
        "kappa_eig_us": "κ CRBA+eigvalsh (µs)",
        "kappa_eig_vs_delta": "κ-eig / δ-O(n)",
    }
    checks = verdicts(table.rows)
    text = [
        "Paper chain of n rods, seeded random configurations; median µs per call in one run, "
        "BLAS on one thread. δ comes from DeNOC's compiled diagonal (one call, preallocated "
        "buffers), also inside the watch; the Pinocchio route is listed for comparison.",
        "",
        markdown_table(table.rows, columns),
        "",
        *[f"- {line}" for line in checks],
    ]
    return SectionResult(
        name="lean",
        title="δ at the cost of its arithmetic",
        tables=[table],
        markdown="\n".join(text),
        headline="\n".join(text),
        summary={"targets": checks},
    )
