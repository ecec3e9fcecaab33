"""Section ``estimators``: how close each cheap estimate of κ comes, and what it costs.

Along seeded sweeps of configurations, every estimator is compared with the exact κ₂
(CRBA + ``eigvalsh``) at each sample (relative error |est − κ|/κ, median and max), and its
cost per evaluation is timed on a few samples (median). Sweeps:

* ``random`` — independent configurations drawn uniformly within the joint limits;
* ``swing`` — for the paper's 4-, 10- and 20-link chains, the samples of their swinging
  trajectories (``gimwatch/scenes/chain_<n>.toml``: straight and horizontal at rest under gravity,
  DOP853 at 1e-10, the first `SWING_DURATION_S` seconds), where κ sweeps from its
  straight-chain maximum through folded configurations.

Estimators (Shah & Saha 2013 and the free Rayleigh bounds, since M_ii = e_iᵀ M e_i):

* ``delta`` — δ = max M_ii / min M_ii ≤ κ (O(n) diagonal);
* ``alpha_delta`` — αδ with α = κ/δ at the first sample (Eq. 15);
* ``alpha_pivot_fwd`` — the forward (LDLᵀ) pivot ratio scaled the same way;
* ``rayleigh_lower`` — max M_ii · max (M⁻¹)_jj ≤ κ (M⁻¹ from Pinocchio's ``computeMinverse``);
* ``rayleigh_upper`` — tr M · tr M⁻¹ ≥ κ;
* ``pocon`` — LAPACK's κ₁ estimate after Cholesky;
* ``lanczos_warm`` — Lanczos on the RNEA/ABA operators at tolerance 1e-3, started from the
  previous sample's eigenvectors.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import pinocchio as pin

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.integrators import chain_scene_table
from gimwatch.bench.krylov_peers import kappa_matrix_free
from gimwatch.bench.plots import plot_pareto
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import time_call
from gimwatch.metrics.conditioning import (
    condition_estimate_1norm,
    condition_number,
    diagonal_ratio,
    pivot_ratio_forward,
)
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.robots import Robot, load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene

__all__ = ["COLUMNS", "ESTIMATORS", "SWING_DURATION_S", "run"]

FULL_ROBOTS = ("chain:4", "chain:10", "chain:20", "ur5", "panda", "talos_arm", "solo12")
QUICK_ROBOTS = ("chain:4", "ur5")
COLUMNS = (
    "robot",
    "nv",
    "sweep",
    "estimator",
    "samples",
    "median_rel_error",
    "max_rel_error",
    "median_ratio",
    "min_ratio",
    "max_ratio",
    "cost_s",
    "kappa_cost_s",
)
ESTIMATORS = (
    "delta",
    "alpha_delta",
    "alpha_pivot_fwd",
    "rayleigh_lower",
    "rayleigh_upper",
    "pocon",
    "lanczos_warm",
)
SWING_DURATION_S = 2.0
SWING_CHAINS = {"chain:4": 4, "chain:10": 10, "chain:20": 20}


def _swing(n: int, count: int, duration_s: float) -> np.ndarray:
    """Configurations at ``count`` samples of the swinging n-link chain (scene file)."""
    table = chain_scene_table(n, duration_s=duration_s)
    table["sample"] = duration_s / (count - 1)
    table["watch"] = {"metrics": []}
    trajectory = run_scene(parse_scene(table, source=f"<bench estimators chain_{n}>"))
    trajectory.raise_for_status()
    return trajectory.q


class _Estimators:
    """The estimators of one sweep; ``alpha`` factors and Lanczos vectors carry over."""

    def __init__(self, robot: Robot, data: pin.Data, first_q: np.ndarray) -> None:
        self.robot, self.data = robot, data
        M0 = gim(robot, first_q, data=data)
        kappa0 = condition_number(M0)
        self.alpha_delta = kappa0 / diagonal_ratio(M0)
        self.alpha_pivot = kappa0 / pivot_ratio_forward(M0)
        self.start: tuple[np.ndarray, np.ndarray] | None = None

    def __call__(self, name: str, q: np.ndarray, *, keep_start: bool = True) -> float:
        robot, data = self.robot, self.data
        if name == "delta":
            return diagonal_ratio(gim_diagonal(robot, q, data=data))
        if name == "alpha_delta":
            return self.alpha_delta * diagonal_ratio(gim_diagonal(robot, q, data=data))
        if name == "alpha_pivot_fwd":
            return self.alpha_pivot * pivot_ratio_forward(gim(robot, q, data=data))
        if name in ("rayleigh_lower", "rayleigh_upper"):
            M = gim(robot, q, data=data)
            Minv = np.array(pin.computeMinverse(robot.model, data, q))
            Minv = np.triu(Minv) + np.triu(Minv, 1).T
            if name == "rayleigh_lower":
                return float(np.max(np.diag(M)) * np.max(np.diag(Minv)))
            return float(np.trace(M) * np.trace(Minv))
        if name == "pocon":
            return condition_estimate_1norm(gim(robot, q, data=data))
        if name == "lanczos_warm":
            result = kappa_matrix_free(robot, q, data=data, seed=0, tol=1e-3, start=self.start)
            if keep_start and result.vector_max is not None and result.vector_min is not None:
                self.start = (result.vector_max, result.vector_min)
            return result.kappa
        raise KeyError(name)

    def from_start(self, q: np.ndarray, start) -> float:
        """``lanczos_warm`` at q from the same ``start`` each time (its timed call)."""
        self.start = start
        return self("lanczos_warm", q, keep_start=False)


def _sweep(context: BenchContext, table: Table, spec: str, sweep: str, count: int) -> None:
    robot = load_robot(spec)
    data = robot.new_data()
    if sweep == "random":
        qs = random_configurations(robot, count, seed=context.seed)
    else:
        duration = 0.2 if context.quick else SWING_DURATION_S
        qs = _swing(SWING_CHAINS[spec], count, duration)
    kappas = np.array([condition_number(gim(robot, q, data=data)) for q in qs])
    estimators = _Estimators(robot, data, qs[0])
    repeats, min_round = (3, 0.001) if context.quick else (5, 0.01)
    timed = qs[1 : 1 + (2 if context.quick else 4)]

    def kappa_at(q: np.ndarray) -> float:
        return condition_number(gim(robot, q, data=data))

    kappa_cost = np.median(
        [
            time_call(partial(kappa_at, q), repeats=repeats, min_round_s=min_round).median_s
            for q in timed
        ]
    )
    for name in ESTIMATORS:
        values = np.array([estimators(name, q) for q in qs])
        ratios = values / kappas
        errors = np.abs(ratios - 1.0)
        costs = []
        for previous, q in zip(qs[: len(timed)], timed, strict=True):
            if name == "lanczos_warm":  # warm start from the previous sample each time
                estimators.start = None
                estimators(name, previous)
                call = partial(estimators.from_start, q, estimators.start)
            else:
                call = partial(estimators, name, q)
            costs.append(time_call(call, repeats=repeats, min_round_s=min_round).median_s)
        table.add(
            robot=robot.name,
            nv=robot.nv,
            sweep=sweep,
            estimator=name,
            samples=len(qs),
            median_rel_error=float(np.median(errors)),
            max_rel_error=float(np.max(errors)),
            median_ratio=float(np.median(ratios)),
            min_ratio=float(np.min(ratios)),
            max_ratio=float(np.max(ratios)),
            cost_s=float(np.median(costs)),
            kappa_cost_s=float(kappa_cost),
        )


def _over_robots(table: Table, name: str) -> dict:
    """One estimator's errors, ratios and relative cost, taken over every robot and sweep."""
    rows = [r for r in table.rows if r["estimator"] == name]
    return {
        "estimator": name,
        "median_rel_error": float(np.median([r["median_rel_error"] for r in rows])),
        "max_rel_error": float(np.max([r["max_rel_error"] for r in rows])),
        "min_ratio": float(np.min([r["min_ratio"] for r in rows])),
        "max_ratio": float(np.max([r["max_ratio"] for r in rows])),
        "cost_vs_kappa": float(np.median([r["cost_s"] / r["kappa_cost_s"] for r in rows])),
    }


def run(context: BenchContext) -> SectionResult:
    """Sweep each robot, score every estimator, write ``estimators.csv`` and the Pareto plot."""
    robots = QUICK_ROBOTS if context.quick else FULL_ROBOTS
    count = 6 if context.quick else 200
    table = Table("estimators", COLUMNS)
    for spec in robots:
        for sweep in ("random", "swing") if spec in SWING_CHAINS else ("random",):
            context.progress(f"  {spec}: {sweep} sweep of {count} samples")
            _sweep(context, table, spec, sweep, count)
    figure = plot_pareto(
        [r for r in table.rows if r["sweep"] == "swing"], context.output / "estimators_pareto.png"
    )
    by_estimator = [_over_robots(table, name) for name in ESTIMATORS]
    columns = {
        "estimator": "estimator",
        "median_rel_error": "median rel. error",
        "max_rel_error": "max rel. error",
        "min_ratio": "min est/κ",
        "max_ratio": "max est/κ",
        "cost_vs_kappa": "cost / cost of κ",
    }
    text = [
        f"Robots {', '.join(robots)}; {count} samples per sweep: random configurations for "
        "every robot, and for the chains also the first "
        f"{0.2 if context.quick else SWING_DURATION_S:g} s of their swinging trajectories "
        "(`swing`, the Pareto plot). Errors are "
        "relative to the exact κ₂ at each sample; the cost is the median time per evaluation "
        "divided by that of κ through CRBA + `eigvalsh` on the same robot (medians over robots "
        "and sweeps).",
        "",
        markdown_table(by_estimator, columns),
        "",
        "Per robot and sweep (`estimators.csv`):",
        "",
        markdown_table(
            table.rows,
            {
                "robot": "robot",
                "nv": "nv",
                "sweep": "sweep",
                "estimator": "estimator",
                "median_rel_error": "median err",
                "max_rel_error": "max err",
                "cost_s": "cost (s)",
                "kappa_cost_s": "κ cost (s)",
            },
        ),
    ]
    return SectionResult(
        name="estimators",
        title="Estimator quality vs cost",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(text[:3]),
        summary={"by_estimator": by_estimator},
    )
