"""Section ``longchain``: very long chains on the O(n) DeNOC path, in time and memory.

Three tables, each measured in one run:

* ``longchain_step`` — median time of one forward-dynamics call (q̈ from q, q̇, τ, gravity)
  by Pinocchio's ABA and by the compiled DeNOC recursion, for n up to the largest chain
  whose Pinocchio Data fits (``DATA_NV_LIMIT``), then DeNOC alone beyond;
* ``longchain_analyze`` — wall time and peak memory (RSS) of a fresh
  ``gimwatch analyze chain:N --json`` process (δ and κ; δ alone at the largest n);
* ``longchain_kappa`` — κ₂/4n⁴ of the straight chain from the dense route (M formed by
  n O(n) products, LAPACK ``eigvalsh``) and from the matrix-free route (the κ tracker's Lanczos
  on M·x and shift-invert (M − σ·1)⁻¹·x, certified): the dense λmin carries an absolute error
  of about eps·λmax, so the dense κ
  stops meaning anything as κ nears 1/eps (≈ 4.5e15, n ≈ 3,300 for κ ≈ 4n⁴).
"""

from __future__ import annotations

import json
import subprocess
import sys
import time
from functools import partial

import numpy as np
import pinocchio as pin
import scipy.linalg

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import time_call
from gimwatch.denoc import ConfigurationState, DenocModel
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.tracker import extreme_eigenvalues
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot

__all__ = ["run"]

_STEP_SIZES = (10, 100, DATA_NV_LIMIT, 1_000, 10_000)
_ANALYZE_SIZES = ((1_000, "all"), (10_000, "all"), (100_000, "diagonal_ratio"))
_KAPPA_SIZES = (100, 500, 1_000, 2_000, 3_000, 4_000)
_QUICK = {"step": (10, 50), "analyze": ((50, "all"),), "kappa": (20, 50)}

_PROBE = """
import contextlib, io, json, sys, time
start = time.perf_counter()
from gimwatch.cli import main
with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
    code = main(sys.argv[1:])
wall = time.perf_counter() - start
# VmHWM, not ru_maxrss: Linux keeps ru_maxrss across exec, so it would report the parent's peak
with open("/proc/self/status") as status:
    peak_kb = next(int(line.split()[1]) for line in status if line.startswith("VmHWM:"))
print(json.dumps({"code": code, "wall_s": wall, "peak_rss_mb": peak_kb / 1024}))
"""


def _step_table(context: BenchContext, sizes) -> Table:
    table = Table("longchain_step", ("n", "method", "median_s", "ratio_to_aba"))
    rng = np.random.default_rng(context.seed)
    gravity = (0.0, -9.81, 0.0)
    for n in sizes:
        spec = chain_spec(n)
        denoc = DenocModel.from_chain(spec)
        q, v, tau = rng.uniform(-0.5, 0.5, n), rng.standard_normal(n), rng.standard_normal(n)
        context.progress(f"  n = {n}: forward dynamics")
        denoc_s = time_call(partial(denoc.forward_dynamics, q, v, tau, gravity=gravity)).median_s
        aba_s = None
        if n <= DATA_NV_LIMIT:
            robot = load_robot(f"chain:{n}")
            model, data = pin.Model(robot.model), robot.new_data()
            model.gravity = pin.Motion(np.array(gravity), np.zeros(3))
            aba_s = time_call(partial(pin.aba, model, data, q, v, tau)).median_s
            table.add(n=n, method="pinocchio_aba", median_s=aba_s, ratio_to_aba=1.0)
            del data
        table.add(
            n=n,
            method="denoc_compiled",
            median_s=denoc_s,
            ratio_to_aba=None if aba_s is None else denoc_s / aba_s,
        )
    return table


def _analyze_table(context: BenchContext, sizes) -> Table:
    table = Table("longchain_analyze", ("n", "metrics", "wall_s", "peak_rss_mb", "exit_code"))
    for n, metrics in sizes:
        argv = ["analyze", f"chain:{n}", "--json", "--backend", "denoc"]
        if metrics != "all":
            argv += ["--metrics", metrics]
        context.progress(f"  analyze chain:{n} ({metrics})")
        done = subprocess.run(
            [sys.executable, "-c", _PROBE, *argv], capture_output=True, text=True, check=False
        )
        probe = json.loads(done.stdout.strip().splitlines()[-1])
        table.add(
            n=n,
            metrics=metrics,
            wall_s=probe["wall_s"],
            peak_rss_mb=probe["peak_rss_mb"],
            exit_code=probe["code"],
        )
    return table


def _kappa_table(context: BenchContext, sizes) -> Table:
    table = Table(
        "longchain_kappa",
        ("n", "route", "kappa", "kappa_over_4n4", "lambda_min", "seconds", "products"),
    )
    for n in sizes:
        model = DenocModel.from_chain(chain_spec(n))
        state = model.state(np.zeros(n))
        assert isinstance(state, ConfigurationState)  # a chain's model is not the lean one
        context.progress(f"  n = {n}: kappa, matrix-free and dense")
        start = time.perf_counter()
        found = extreme_eigenvalues(state, seed=context.seed)
        seconds = time.perf_counter() - start
        table.add(
            n=n,
            route="matrix_free_lanczos",
            kappa=found.kappa,
            kappa_over_4n4=found.kappa / (4 * n**4),
            lambda_min=found.lambda_min,
            seconds=seconds,
            products=found.products,
        )
        start = time.perf_counter()
        values = scipy.linalg.eigvalsh(state.dense())
        seconds = time.perf_counter() - start
        kappa = extreme_ratio(values) if values[0] > 0 else float("inf")
        table.add(
            n=n,
            route="dense_eigvalsh",
            kappa=kappa,
            kappa_over_4n4=kappa / (4 * n**4),
            lambda_min=float(values[0]),
            seconds=seconds,
            products=n,
        )
    return table


def run(context: BenchContext) -> SectionResult:
    """Measure the three tables and write the section's report."""
    step = _step_table(context, _QUICK["step"] if context.quick else _STEP_SIZES)
    analyze = _analyze_table(context, _QUICK["analyze"] if context.quick else _ANALYZE_SIZES)
    kappa = _kappa_table(context, _QUICK["kappa"] if context.quick else _KAPPA_SIZES)
    step_md = markdown_table(
        step.rows,
        {
            "n": "n",
            "method": "forward dynamics",
            "median_s": "s per call",
            "ratio_to_aba": "÷ Pinocchio ABA",
        },
    )
    analyze_md = markdown_table(
        analyze.rows,
        {"n": "n", "metrics": "metrics", "wall_s": "wall (s)", "peak_rss_mb": "peak RSS (MB)"},
    )
    kappa_md = markdown_table(
        kappa.rows,
        {
            "n": "n",
            "route": "route",
            "kappa_over_4n4": "κ / 4n⁴",
            "lambda_min": "λmin",
            "seconds": "s",
            "products": "O(n) products",
        },
    )
    text = (
        "The O(n) path never builds Pinocchio's Data (memory ∝ n³) nor the dense M "
        "(`gimwatch/denoc/fused.py`, numba).\n\n"
        f"Forward dynamics per call:\n\n{step_md}\n\n"
        f"`gimwatch analyze chain:N --json --backend denoc`, a fresh process each "
        f"(import and JIT-cache load included):\n\n{analyze_md}\n\n"
        "κ₂ of the straight chain, dense vs matrix-free (the dense λmin has an absolute error "
        f"of about eps·λmax):\n\n{kappa_md}\n"
    )
    summary = {
        "analyze": {
            str(r["n"]): {"wall_s": r["wall_s"], "peak_rss_mb": r["peak_rss_mb"]}
            for r in analyze.rows
        },
        "step_ratio_denoc_to_aba": {
            str(r["n"]): r["ratio_to_aba"] for r in step.rows if r["method"] == "denoc_compiled"
        },
    }
    return SectionResult(
        name="longchain",
        title="Very long chains on the O(n) path",
        tables=[step, analyze, kappa],
        markdown=text,
        headline=analyze_md,
        summary=summary,
    )
