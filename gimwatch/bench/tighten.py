"""Section ``tighten``: does ``on_alarm = "tighten"`` buy accuracy per unit of time?

On hard chains (gravity swing from rest, 2 s), each run's error is the largest joint-angle
difference from a DOP853 run at rtol = atol = 1e-13, over the samples. Fixed tolerances
(rtol = atol = 1e-4 … 1e-10) trace the work-precision curve of RK45; ``tighten`` starts at
1e-5 and watches κ with the threshold at κ(t0)/10: the alarm is on from the first sample
and the tolerances fall as ``rtol₀ · threshold / κ``, tighter as the conditioning worsens.
The wall time includes the watch (one eigen-solve per sample). It buys accuracy per unit
of time when its point lies below the fixed-tolerance curve (less error for the same wall
time or RHS count).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.report import markdown_table
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import Simulation

__all__ = ["COLUMNS", "run"]

COLUMNS = ("case", "mode", "rtol0", "error_rad", "wall_time_s", "rhs_evaluations", "actions")
_CASES: dict[str, dict[str, Any]] = {
    "straight-20": {"n": 20},
    "feather-root-12": {
        "n": 12,
        "mass_kg": [1e-3] + [2.2] * 10 + [100.0],
        "length_m": [0.01] + [1.0] * 11,
    },
    "heavy-root-12": {"n": 12, "mass_kg": [1000.0] + [2.2] * 10 + [1e-3]},
}
_FIXED = (1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10)
_START = 1e-5


def _scene(chain: dict, duration: float, integrator: dict, watch: dict | None = None):
    table = {
        "robot": chain,
        "duration": duration,
        "sample": 0.02,
        "q": 0.05,
        "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
        "integrator": integrator,
    }
    if watch:
        table["watch"] = watch
    return parse_scene(table, source="<bench tighten>")


def _run(scene):
    run = Simulation(scene).run()
    if run.status != "completed":
        raise RuntimeError(f"bench tighten: {run.status}: {run.message}")
    return run


def _add(table: Table, case: str, mode: str, rtol0: float, run, reference) -> float:
    """Add a row for ``run`` against ``reference``; return its error (rad)."""
    error = float(np.max(np.abs(run.q - reference.q)))
    table.add(
        case=case,
        mode=mode,
        rtol0=rtol0,
        error_rad=error,
        wall_time_s=run.wall_time_s,
        rhs_evaluations=run.rhs_evaluations,
        actions=len(run.actions) if mode == "tighten" else 0,
    )
    return error


def _case(context: BenchContext, table: Table, name: str, chain: dict) -> dict:
    """Run one hard chain: the reference, the fixed tolerances, then ``tighten``."""
    duration = 0.5 if context.quick else 2.0
    context.progress(f"  {name}: reference")
    reference = _run(_scene(chain, duration, {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}))
    kappa0 = _run(_scene(chain, 0.02, {"method": "DOP853"}, {"metrics": ["kappa"]})).watch[
        "watch_kappa"
    ][0]
    points = []
    for rtol in _FIXED[:3] if context.quick else _FIXED:
        run = _run(_scene(chain, duration, {"method": "RK45", "rtol": rtol, "atol": rtol}))
        points.append((run.wall_time_s, _add(table, name, "fixed", rtol, run, reference)))
    watch = {"metrics": ["kappa"], "alarm_threshold": 0.1 * kappa0, "on_alarm": "tighten"}
    run = _run(_scene(chain, duration, {"method": "RK45", "rtol": _START, "atol": _START}, watch))
    error = _add(table, name, "tighten", _START, run, reference)
    # the fixed-tolerance error at the same wall time (log-log interpolation)
    times, errors = np.log([p[0] for p in points]), np.log([p[1] for p in points])
    order = np.argsort(times)
    at_same_time = float(np.exp(np.interp(np.log(run.wall_time_s), times[order], errors[order])))
    return {
        "case": name,
        "kappa0": float(kappa0),
        "tighten_error": error,
        "fixed_error_same_time": at_same_time,
        "ratio": error / at_same_time,
    }


def run(context: BenchContext) -> SectionResult:
    """Time and score fixed tolerances and ``tighten`` on each hard chain."""
    table = Table("tighten", COLUMNS)
    verdicts = [_case(context, table, name, chain) for name, chain in _CASES.items()]
    text = [
        "Largest joint-angle error (rad) vs a DOP853 run at 1e-13, RK45, 2 s gravity swing.",
        "",
        markdown_table(table.rows, {c: c for c in COLUMNS}),
        "",
        "`tighten` error / fixed-tolerance error at the same wall time (log-log interpolated; "
        "< 1 means tighten buys accuracy per unit of time):",
        "",
        markdown_table(verdicts, {k: k for k in verdicts[0]}),
    ]
    return SectionResult(
        name="tighten",
        title="Tightening the tolerance on alarm",
        tables=[table],
        markdown="\n".join(text),
        headline="",
        summary={"tighten_vs_fixed_same_time": {v["case"]: v["ratio"] for v in verdicts}},
    )
