"""Section ``denoc``: what gimwatch's DeNOC (NumPy) costs against Pinocchio (C++).

For each chain size n (the paper's rod chains ``chain:n``, one seeded random state) it times
the GIM (DeNOC Eqs. 11–13 vs ``pinocchio.crba``), its O(n) diagonal (no Pinocchio
counterpart: ``gimwatch.model.inertia.gim_diagonal`` is listed for scale), inverse dynamics (vs
``rnea``) and forward dynamics (Saha's UDUᵀ recursion vs ``aba``): median time per call
(:func:`gimwatch.bench.timing.time_call`) and the ratio DeNOC / Pinocchio.

Pinocchio's Data grows as nv³; above nv = 400 it is built only when it fits in half the
available memory (:func:`gimwatch.bench.timing.data_if_it_fits`) and freed before the next
size, else Pinocchio is not timed at that size and the row says so.
"""

from __future__ import annotations

import gc
from collections.abc import Callable

import numpy as np
import pinocchio as pin

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.plots import plot_denoc_cost
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import data_if_it_fits, time_call
from gimwatch.crosscheck import denoc_model
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import load_robot, random_configurations

__all__ = ["COLUMNS", "FULL_SIZES", "QUICK_SIZES", "run"]

FULL_SIZES = (10, 100, 500)
QUICK_SIZES = (4,)
COLUMNS = ("n", "quantity", "denoc_us", "pinocchio_us", "ratio", "note")


def _cases(dm, robot, data, q, v, a, tau) -> dict[str, tuple[Callable, Callable | None]]:
    """(DeNOC call, Pinocchio call or None) per quantity, bound to one state."""
    model = robot.model
    return {
        "gim": (lambda: dm.gim(q), lambda: pin.crba(model, data, q)),
        "gim_diagonal": (
            lambda: dm.gim_diagonal(q),
            lambda: gim_diagonal(robot, q, data=data),
        ),
        "inverse_dynamics": (
            lambda: dm.inverse_dynamics(q, v, a),
            lambda: pin.rnea(model, data, q, v, a),
        ),
        "forward_dynamics": (
            lambda: dm.forward_dynamics(q, v, tau),
            lambda: pin.aba(model, data, q, v, tau),
        ),
    }


def measure(context: BenchContext) -> Table:
    """Time DeNOC and Pinocchio per size and quantity."""
    sizes = QUICK_SIZES if context.quick else FULL_SIZES
    repeats, min_round = (3, 0.002) if context.quick else (5, 0.05)
    table = Table("denoc", COLUMNS)
    for n in sizes:
        robot = load_robot(f"chain:{n}")
        dm = denoc_model(robot)
        rng = np.random.default_rng(context.seed)
        q = random_configurations(robot, 1, seed=context.seed)[0]
        v, a, tau = (rng.standard_normal(robot.nv) for _ in range(3))
        data = data_if_it_fits(robot)
        note = "" if data is not None else "Pinocchio not timed: its Data would not fit in memory"
        for quantity, (denoc_call, pin_call) in _cases(dm, robot, data, q, v, a, tau).items():
            context.progress(f"  chain:{n}: {quantity}")
            denoc_us = time_call(denoc_call, repeats=repeats, min_round_s=min_round).median_s
            pin_us = (
                time_call(pin_call, repeats=repeats, min_round_s=min_round).median_s
                if data is not None
                else float("nan")
            )
            why = note or (
                "Pinocchio side: gimwatch's O(n) diagonal" if quantity == "gim_diagonal" else ""
            )
            table.add(
                n=n,
                quantity=quantity,
                denoc_us=denoc_us * 1e6,
                pinocchio_us=pin_us * 1e6,
                ratio=denoc_us / pin_us,
                note=why,
            )
        del data
        gc.collect()
    return table


def run(context: BenchContext) -> SectionResult:
    """Measure, plot ``denoc_cost.png`` and summarise the ratios."""
    table = measure(context)
    figure = plot_denoc_cost(table.rows, context.output / "denoc_cost.png")
    columns = {
        "n": "n",
        "quantity": "quantity",
        "denoc_us": "DeNOC (µs)",
        "pinocchio_us": "Pinocchio (µs)",
        "ratio": "DeNOC / Pinocchio",
        "note": "note",
    }
    fd = {r["n"]: r["ratio"] for r in table.rows if r["quantity"] == "forward_dynamics"}
    text = [
        "Rod chains `chain:n`, one seeded random state; median µs per call. DeNOC is "
        "gimwatch's own implementation, no Pinocchio: the O(n) operations (diagonal, inverse "
        "and forward dynamics) run its compiled recursions for fixed bases, the dense GIM its "
        "per-depth NumPy recursions; Pinocchio is C++.",
        "",
        markdown_table(table.rows, columns),
    ]
    return SectionResult(
        name="denoc",
        title="DeNOC vs Pinocchio cost",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(text),
        summary={"forward_dynamics_ratio": {str(k): v for k, v in fd.items()}},
    )
