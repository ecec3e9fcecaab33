"""Section ``denoc``: what gimwatch's DeNOC (compiled) costs against Pinocchio (C++).

For each chain size n (the paper's rod chains ``chain:n``, fixed, and the same chain on a
free-flyer with a rod as its base body; one seeded random state) it times
the GIM (DeNOC Eqs. 11–13 vs ``pinocchio.crba``), its O(n) diagonal (no Pinocchio
counterpart: ``gimwatch.model.inertia.gim_diagonal`` is listed for scale), inverse dynamics (vs
``rnea``) and forward dynamics (Saha's UDUᵀ recursion vs ``aba``; through the checked
``DenocModel`` API and through ``DenocModel.lean()``, one compiled call): median time per call
(`gimwatch.bench.timing.time_call`) and the ratio DeNOC / Pinocchio.

Pinocchio's Data grows as nv³; above nv = 400 it is built only when it fits in half the
available memory (`gimwatch.bench.timing.data_if_it_fits`) and freed before the next
size, else Pinocchio is not timed at that size and the row says so.
"""

from __future__ import annotations

import tempfile
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult
from gimwatch.bench.compare import Case, Comparison, Rounds, run_comparison
from gimwatch.bench.plots import plot_denoc_cost
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import data_if_it_fits
from gimwatch.crosscheck import denoc_model
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

__all__ = ["COLUMNS", "COMPARISON", "FULL_SIZES", "QUICK_SIZES", "run"]

FULL_SIZES = (10, 100, 500)
QUICK_SIZES = (4,)
COLUMNS = ("n", "quantity", "denoc_us", "pinocchio_us", "ratio", "note")


_GRAVITY = np.array([0.0, 0.0, -9.81])  # Pinocchio's default, as in the models timed here
#: A 2.2 kg, 1 m rod as the floating chain's base body (the generated chain's is massless,
#: which leaves M singular on a free-flyer: the base could spin about joint 1's axis for free).
_BASE_INERTIAL = (
    '<link name="base_link"><inertial><origin xyz="0.5 0 0"/><mass value="2.2"/>'
    '<inertia ixx="0.0011" iyy="0.18" izz="0.18" ixy="0" ixz="0" iyz="0"/></inertial></link>'
)


def floating_chain(n: int, folder: Path):
    """The paper's n-rod chain on a free-flyer, its base a rod too (URDF written to folder)."""
    xml = generate_chain_urdf(chain_spec(n)).replace('<link name="base_link"/>', _BASE_INERTIAL)
    path = folder / f"floating_chain_{n}.urdf"
    path.write_text(xml, encoding="utf-8")
    return load_robot(path, floating=True)


def _lean_case(dm, robot, data, q, v, tau) -> tuple[Callable, Callable]:
    """The lean call (one compiled call, preallocated output) and Pinocchio's ABA."""
    lean, out, model = dm.lean(), np.empty(robot.nv), robot.model
    return (
        lambda: lean.forward_dynamics(q, v, tau, _GRAVITY, out),
        lambda: pin.aba(model, data, q, v, tau),
    )


def _cases(dm, robot, data, q, v, a, tau) -> dict[str, tuple[Callable, Callable | None]]:
    """(DeNOC call, Pinocchio call or None) per quantity, bound to one state."""
    model = robot.model
    if robot.floating:
        return {
            "forward_dynamics_floating": (
                lambda: dm.forward_dynamics(q, v, tau),
                lambda: pin.aba(model, data, q, v, tau),
            ),
            "forward_dynamics_floating_lean": _lean_case(dm, robot, data, q, v, tau),
        }
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
        "forward_dynamics_lean": _lean_case(dm, robot, data, q, v, tau),
    }


def _case(size: tuple[int, bool], context: BenchContext) -> Case:
    n, floating = size
    folder = tempfile.TemporaryDirectory(prefix="gimwatch-bench-")  # removed with the case
    robot = floating_chain(n, Path(folder.name)) if floating else load_robot(f"chain:{n}")
    dm = denoc_model(robot)
    rng = np.random.default_rng(context.seed)
    q = random_configurations(robot, 1, seed=context.seed)[0]
    v, a, tau = (rng.standard_normal(robot.nv) for _ in range(3))
    data = data_if_it_fits(robot)
    cases = _cases(dm, robot, data, q, v, a, tau)
    calls: dict[str, Callable[[], object] | None] = {}
    for quantity, (denoc_call, pin_call) in cases.items():
        calls[f"{quantity}, DeNOC"] = denoc_call
        calls[f"{quantity}, Pinocchio"] = pin_call if data is not None else None
    facts = {"n": n, "quantities": tuple(cases), "folder": folder, "timed_pinocchio": data}
    return Case(f"chain:{n}{' floating' * floating}", calls, facts)


def _rows(case: Case) -> Iterator[dict]:
    note = (
        ""
        if case.facts["timed_pinocchio"] is not None
        else "Pinocchio not timed: its Data would not fit in memory"
    )
    for quantity in case.facts["quantities"]:
        denoc = case.timings[f"{quantity}, DeNOC"]
        pinocchio = case.timings[f"{quantity}, Pinocchio"]
        denoc_s = denoc.median_s if denoc else float("nan")
        pin_s = pinocchio.median_s if pinocchio else float("nan")
        why = note or (
            "Pinocchio side: gimwatch's O(n) diagonal" if quantity == "gim_diagonal" else ""
        )
        yield {
            "n": case.facts["n"],
            "quantity": quantity,
            "denoc_us": denoc_s * 1e6,
            "pinocchio_us": pin_s * 1e6,
            "ratio": denoc_s / pin_s,
            "note": why,
        }


def _sizes(ns: tuple[int, ...]) -> tuple[tuple[int, bool], ...]:
    return tuple((n, False) for n in ns) + tuple((n, True) for n in ns)


#: DeNOC against Pinocchio per quantity, on fixed then floating chains of each size.
COMPARISON = Comparison(
    "denoc",
    COLUMNS,
    _sizes(FULL_SIZES),
    _sizes(QUICK_SIZES),
    _case,
    _rows,
    Rounds(repeats=5, min_round_s=0.05),
)


#: Issue 16: DeNOC forward dynamics ≤ 3× ABA at n = 10 and ≤ 1.2× at n ≥ 100 (both bases).
FD_TARGETS = {10: 3.0, 100: 1.2, 500: 1.2}


def verdicts(rows: list[dict]) -> list[str]:
    """The lean forward dynamics against the lean-FD targets (one line per size and base)."""
    lines = []
    for row in rows:
        if row["quantity"] in ("forward_dynamics_lean", "forward_dynamics_floating_lean"):
            limit = FD_TARGETS.get(row["n"])
            if limit is None or not np.isfinite(row["ratio"]):
                continue
            base = "floating" if "floating" in row["quantity"] else "fixed"
            verdict = "met" if row["ratio"] <= limit else "not met"
            lines.append(
                f"n = {row['n']}, {base} base: DeNOC FD / ABA = {row['ratio']:.3g} "
                f"(target ≤ {limit:g}: {verdict})"
            )
    return lines


def run(context: BenchContext) -> SectionResult:
    """Measure, plot ``denoc_cost.png`` and summarise the ratios."""
    # BLAS on one thread, set here: the CLI's limit misses an OpenBLAS loaded after it
    with threadpool_limits(limits=1, user_api="blas"):
        table = run_comparison(COMPARISON, context)
    figure = plot_denoc_cost(table.rows, context.output / "denoc_cost.png")
    columns = {
        "n": "n",
        "quantity": "quantity",
        "denoc_us": "DeNOC (µs)",
        "pinocchio_us": "Pinocchio (µs)",
        "ratio": "DeNOC / Pinocchio",
        "note": "note",
    }
    fd = {
        f"{r['quantity']}:{r['n']}": r["ratio"]
        for r in table.rows
        if r["quantity"].startswith("forward_dynamics")
    }
    text = [
        "Rod chains `chain:n`, one seeded random state; median µs per call. DeNOC is "
        "gimwatch's own implementation, no Pinocchio: the O(n) operations (diagonal, inverse "
        "and forward dynamics) run its compiled recursions for fixed bases, the dense GIM its "
        "per-depth NumPy recursions; Pinocchio is C++.",
        "",
        markdown_table(table.rows, columns),
        "",
        "`*_lean` rows: `DenocModel.lean()`, one compiled call with preallocated buffers (no "
        "argument checks); the other rows go through `DenocModel`'s checked API. Floating: "
        "the chain on a free-flyer, its base a 2.2 kg rod.",
        "",
        *[f"- {line}" for line in verdicts(table.rows)],
    ]
    return SectionResult(
        name="denoc",
        title="DeNOC vs Pinocchio cost",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(text),
        summary={
            "forward_dynamics_ratio": {str(k): v for k, v in fd.items()},
            "targets": verdicts(table.rows),
        },
    )
