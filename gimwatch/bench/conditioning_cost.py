"""Section ``conditioning``: what κ, δ and their estimates cost as the chain grows.

For the paper's chain of n rods (n = 4 … 500) at one seeded random configuration, each
method is timed (median per call) and compared with the exact κ₂ from CRBA + ``eigvalsh``:

* ``kappa_crba_eigvalsh`` — M by CRBA, κ₂ = λmax/λmin by LAPACK syevr (O(n³));
* ``delta_crba_diagonal`` — M by CRBA, δ from its diagonal (O(n²));
* ``delta_on_diagonal`` — δ from
  [`gim_diagonal`][gimwatch.model.inertia.gim_diagonal], O(n), no M;
* ``pocon_cholesky`` — M by CRBA, Cholesky, LAPACK pocon's κ₁ estimate (O(n³) + O(n²));
* ``kappa_lanczos_*`` — κ₂ from Lanczos on the RNEA (M·x) and ABA (M⁻¹·x) operators
  ([`kappa_matrix_free`][gimwatch.bench.krylov_peers.kappa_matrix_free]), at ARPACK tolerance 1e-10
  and 1e-3.

Pinocchio's Data grows as nv³ (≈ 1.2 GB at nv = 300), so above nv = 400 a fresh Data is
built for that size only when the machine has room for it, and freed before the next size.
"""

from __future__ import annotations

from functools import partial

import numpy as np
import scipy.linalg

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.compare import Case, Comparison, run_comparison
from gimwatch.bench.krylov_peers import kappa_matrix_free
from gimwatch.bench.plots import plot_cost_vs_n
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import data_if_it_fits
from gimwatch.metrics.conditioning import (
    condition_estimate_1norm,
    condition_number,
    diagonal_ratio,
    extreme_ratio,
)
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

__all__ = ["COLUMNS", "COMPARISON", "FULL_SIZES", "QUICK_SIZES", "run"]

FULL_SIZES = (4, 10, 20, 50, 100, 200, 300, 400, 500)
QUICK_SIZES = (4, 8)
COLUMNS = (
    "n",
    "method",
    "median_s",
    "min_s",
    "calls_per_round",
    "estimate",
    "kappa_exact",
    "ratio_to_kappa",
    "rel_error",
    "products",
)


def _methods(robot, q, data) -> dict:
    def kappa_eig() -> float:
        return condition_number(gim(robot, q, data=data))

    def delta_crba() -> float:
        return diagonal_ratio(np.diag(gim(robot, q, data=data)))

    def delta_on() -> float:
        return diagonal_ratio(gim_diagonal(robot, q, data=data))

    def pocon() -> float:
        return condition_estimate_1norm(gim(robot, q, data=data))

    def lanczos(tol: float) -> float:
        return kappa_matrix_free(robot, q, data=data, seed=0, tol=tol).kappa

    return {
        "kappa_crba_eigvalsh": kappa_eig,
        "delta_crba_diagonal": delta_crba,
        "delta_on_diagonal": delta_on,
        "pocon_cholesky": pocon,
        "kappa_lanczos_1e-10": partial(lanczos, 1e-10),
        "kappa_lanczos_1e-3": partial(lanczos, 1e-3),
    }


def _case(n: int, context: BenchContext) -> Case | None:
    robot = load_robot(f"chain:{n}")
    data = data_if_it_fits(robot)
    if data is None:
        context.progress(f"  n = {n}: skipped, a Pinocchio Data would not fit in memory")
        return None
    q = random_configurations(robot, 1, seed=context.seed)[0]
    kappa = extreme_ratio(scipy.linalg.eigvalsh(gim(robot, q, data=data)))
    methods = _methods(robot, q, data)
    facts = {"n": n, "robot": robot, "q": q, "data": data, "kappa": kappa, "methods": methods}
    return Case(f"n = {n}", methods, facts)


def _rows(case: Case) -> list[dict]:
    f, rows = case.facts, []
    for method, fn in f["methods"].items():
        timing, estimate = case.timings[method], float(fn())
        assert timing is not None  # every method is timed at every size it runs
        products = (
            kappa_matrix_free(
                f["robot"], f["q"], data=f["data"], seed=0, tol=float(method.split("_")[-1])
            ).products
            if method.startswith("kappa_lanczos")
            else None
        )
        rows.append(
            {
                "n": f["n"],
                "method": method,
                "median_s": timing.median_s,
                "min_s": timing.min_s,
                "calls_per_round": timing.number,
                "estimate": estimate,
                "kappa_exact": f["kappa"],
                "ratio_to_kappa": estimate / f["kappa"],
                "rel_error": abs(estimate - f["kappa"]) / f["kappa"],
                "products": products,
            }
        )
    return rows


#: Each method against the exact κ, per chain size.
COMPARISON = Comparison("conditioning", COLUMNS, FULL_SIZES, QUICK_SIZES, _case, _rows)


def run(context: BenchContext) -> SectionResult:
    """Time each method against n and write ``conditioning.csv`` and its plot."""
    table = run_comparison(COMPARISON, context)
    sizes = QUICK_SIZES if context.quick else FULL_SIZES
    measured = {row["n"] for row in table.rows}
    return _result(context, table, [n for n in sizes if n not in measured])


def _median(table: Table, n: int, method: str) -> float | None:
    for row in table.rows:
        if row["n"] == n and row["method"] == method:
            return row["median_s"]
    return None


def _cost_row(table: Table, n: int, methods: list[str]) -> dict:
    """µs per method at size n, and the speedup of δ on the diagonal over κ by eig."""
    row: dict = {"n": n}
    for method in methods:
        seconds = _median(table, n, method)
        row[method] = None if seconds is None else seconds * 1e6
    base, cheap = _median(table, n, "kappa_crba_eigvalsh"), _median(table, n, "delta_on_diagonal")
    row["speedup"] = base / cheap if base and cheap else None
    return row


def _result(context: BenchContext, table: Table, skipped: list[int]) -> SectionResult:
    figure = context.output / "conditioning_cost.png"
    plot_cost_vs_n(table.rows, figure)
    sizes = sorted({row["n"] for row in table.rows})
    methods = list(dict.fromkeys(row["method"] for row in table.rows))
    cost_rows = [_cost_row(table, n, methods) for n in sizes]
    columns = {"n": "n", **{m: f"{m} (µs)" for m in methods}, "speedup": "κ-eig / δ-O(n)"}
    accuracy_rows = [r for r in table.rows if r["n"] == sizes[-1]]
    speedups = {r["n"]: r["speedup"] for r in cost_rows}
    checks = []
    for n, needed in ((200, 30), (500, 150)):
        got = speedups.get(n)
        if got is not None:
            verdict = "met" if got >= needed else "NOT met"
            checks.append(f"n = {n}: {got:.0f}x (target ≥ {needed}x: {verdict})")
    summary = {"speedup_delta_on_vs_kappa_eig": speedups, "acceptance": checks}
    text = [
        "Paper chain (2.2 kg, 1 m rods), one seeded random configuration per n. Cost is the "
        "median time per call, in µs; the last column is the cost of κ by CRBA + `eigvalsh` "
        "divided by the cost of δ from the O(n) diagonal.",
        "",
        markdown_table(cost_rows, columns),
        "",
        "δ through the O(n) diagonal vs κ through CRBA + eigensolver: " + "; ".join(checks) + ".",
    ]
    if skipped:
        text.append(f"Skipped (a Pinocchio Data would not fit in memory): n = {skipped}.")
    text += [
        "",
        f"Accuracy against the exact κ at n = {sizes[-1]} (δ is a lower bound; pocon estimates "
        "κ₁, which lies within a factor n of κ₂):",
        "",
        markdown_table(
            accuracy_rows,
            {
                "method": "method",
                "estimate": "estimate",
                "ratio_to_kappa": "estimate / κ",
                "rel_error": "relative error",
                "products": "RNEA+ABA calls",
            },
        ),
    ]
    markdown = "\n".join(text)
    headline = "\n".join(text[:5])
    return SectionResult(
        name="conditioning",
        title="Conditioning cost vs n",
        tables=[table],
        figures=[figure],
        markdown=markdown,
        headline=headline,
        summary=summary,
    )
