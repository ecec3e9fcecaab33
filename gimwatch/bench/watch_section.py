"""Section ``watch``: what the GIM watch costs per simulation step.

The paper's chain of n rods swings under gravity with fixed-step RK4 (4 ABA calls per
step, the ``aba`` backend); the watch runs at the samples only, every
`STEPS_PER_SAMPLE` steps, as in the scenes. Watches (`WATCHES`): none, δ
(O(n) diagonal), αδ (Eq. 15, one eigen-solve at t0), κ by CRBA + eigensolver, and κ by
the κ tracker at tolerance 1e-3 on O(n) products (``kappa_lanczos``).

Per (n, watch) the section reports

* ``step_us`` — a whole run timed (median of ``repeats`` runs) divided by its steps, and
  ``run_overhead`` — its excess over the bare run (the difference of two run times: noisy);
* ``sample_us`` — one [`sample`][gimwatch.watch.watch.Watch.sample]
  timed alone on the bare run's configurations, in order (so Lanczos warm-starts as in a run),
  median of passes;
* ``sample_vs_step`` = sample_us / bare step_us — the watch's cost if it sampled every step;
* ``amortized`` = sample_us / (STEPS_PER_SAMPLE x bare step_us) — its share at the scenes'
  sampling rate;
* ``sample_vs_aba_call`` — sample_us against one ``pinocchio.aba`` call.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.plots import plot_watch_cost
from gimwatch.bench.report import markdown_table
from gimwatch.bench.timing import time_call
from gimwatch.model.robots import load_robot
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import Simulation
from gimwatch.watch.watch import Watch

__all__ = ["COLUMNS", "STEPS_PER_SAMPLE", "WATCHES", "run"]

#: Watch configurations: label -> watched metrics.
WATCHES: dict[str, tuple[str, ...]] = {
    "none": (),
    "delta": ("diagonal_ratio",),
    "alpha_delta": ("scaled_diagonal_ratio",),
    "kappa_eig": ("kappa",),
    "kappa_lanczos": ("kappa_lanczos",),
}
STEPS_PER_SAMPLE = 10
DT_S = 1e-3
#: Target: watching δ costs under this fraction of a bare ABA step (20 links).
DELTA_TARGET = 0.15
COLUMNS = (
    "n",
    "watch",
    "steps",
    "samples",
    "step_us",
    "run_overhead",
    "sample_us",
    "sample_vs_step",
    "amortized",
    "aba_call_us",
    "sample_vs_aba_call",
)


def _scene(n: int, metrics: tuple[str, ...], steps: int):
    return parse_scene(
        {
            "robot": f"chain:{n}",
            "duration": steps * DT_S,
            "sample": STEPS_PER_SAMPLE * DT_S,
            "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
            "integrator": {"method": "RK4", "dt": DT_S},
            "dynamics": {"backend": "aba"},
            "watch": {"metrics": list(metrics)},
        },
        source=f"<bench chain_{n}>",
    )


def _time_run(scene, repeats: int):
    times, trajectory = [], None
    for _ in range(repeats):
        simulation = Simulation(scene)
        start = time.perf_counter()
        trajectory = simulation.run()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), trajectory


def _time_samples(robot, metrics: tuple[str, ...], qs: np.ndarray, repeats: int) -> float:
    """Median over passes of the mean time of one sample (µs), each pass a fresh Watch."""
    if not metrics:
        return 0.0
    passes = []
    for _ in range(repeats):
        watch = Watch(robot, metrics)
        watch.sample(0.0, qs[0])  # t0 (α's one eigen-solve) is not a per-step cost
        start = time.perf_counter()
        for k, q in enumerate(qs[1:], start=1):
            watch.sample(float(k), q)
        passes.append((time.perf_counter() - start) / (len(qs) - 1))
    return float(np.median(passes)) * 1e6


def _aba_call_us(robot, seed: int, quick: bool) -> float:
    model, data = robot.model, robot.new_data()
    rng = np.random.default_rng(seed)
    q, v, tau = rng.standard_normal((3, robot.nv))
    timing = time_call(
        lambda: pin.aba(model, data, q, v, tau), repeats=3 if quick else 7, min_round_s=0.02
    )
    return timing.median_s * 1e6


def measure(context: BenchContext) -> Table:
    """Time every watch on every chain; one row per (n, watch)."""
    lengths = (4,) if context.quick else (4, 10, 20)
    steps, repeats = (40, 2) if context.quick else (2000, 5)
    table = Table("watch", COLUMNS)
    for n in lengths:
        robot = load_robot(f"chain:{n}")
        aba_us = _aba_call_us(robot, context.seed, context.quick)
        bare_step = configurations = None
        for label, metrics in WATCHES.items():
            context.progress(f"  chain:{n}: watch {label}")
            wall, trajectory = _time_run(_scene(n, metrics, steps), repeats)
            step_us = wall / trajectory.steps * 1e6
            if bare_step is None:
                bare_step, configurations = step_us, trajectory.q
            assert configurations is not None  # the first watch's run set them
            sample_us = _time_samples(robot, metrics, configurations, repeats)
            table.add(
                n=n,
                watch=label,
                steps=trajectory.steps,
                samples=int(trajectory.t.size),
                step_us=step_us,
                run_overhead=step_us / bare_step - 1.0,
                sample_us=sample_us,
                sample_vs_step=sample_us / bare_step,
                amortized=sample_us / (STEPS_PER_SAMPLE * bare_step),
                aba_call_us=aba_us,
                sample_vs_aba_call=sample_us / aba_us,
            )
    return table


def run(context: BenchContext) -> SectionResult:
    """Measure, plot ``watch_cost.png`` and summarise against the δ-cost target."""
    # BLAS on one thread, set here: the CLI's limit misses an OpenBLAS loaded after it
    with threadpool_limits(limits=1, user_api="blas"):
        table = measure(context)
    figure = plot_watch_cost(table.rows, context.output / "watch_cost.png")
    n_max = max(r["n"] for r in table.rows)
    delta = next(r for r in table.rows if r["n"] == n_max and r["watch"] == "delta")
    met = delta["sample_vs_step"] < DELTA_TARGET
    verdict = (
        f"Target: watching δ costs under {DELTA_TARGET:.0%} of a bare ABA step for "
        f"a 20-link chain. Measured at n = {n_max}: one δ sample costs "
        f"{delta['sample_us']:.3g} µs = {delta['sample_vs_step']:.1%} of a bare RK4 + ABA "
        f"step ({delta['sample_us'] / delta['sample_vs_step']:.3g} µs) if it sampled every "
        f"step — **{'met' if met else 'not met'}**; {delta['amortized']:.1%} amortized at one "
        f"sample every {STEPS_PER_SAMPLE} steps; {delta['sample_vs_aba_call']:.2g}x one "
        f"`pinocchio.aba` call ({delta['aba_call_us']:.3g} µs)."
    )
    columns = {
        "n": "n",
        "watch": "watch",
        "step_us": "step (µs)",
        "run_overhead": "run overhead",
        "sample_us": "one sample (µs)",
        "sample_vs_step": "sample / bare step",
        "amortized": f"amortized (1 per {STEPS_PER_SAMPLE} steps)",
        "sample_vs_aba_call": "sample / aba call",
    }
    text = [
        f"RK4 at dt = {DT_S:g} s with the `aba` backend, chain of n rods under gravity, a watch "
        f"sample every {STEPS_PER_SAMPLE} steps. `step` is a whole run over its steps (median "
        "of runs; `run overhead` is its excess over the bare run, a noisy difference of two "
        "run times); `one sample` is `Watch.sample` timed alone on the run's configurations "
        "(Lanczos warm-started from the previous sample, α calibrated before timing).",
        "",
        markdown_table(table.rows, columns),
        "",
        verdict,
    ]
    return SectionResult(
        name="watch",
        title="Cost of the watch per step",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(
            [
                markdown_table([r for r in table.rows if r["n"] == n_max], columns),
                "",
                verdict,
            ]
        ),
        summary={
            "delta_sample_vs_step": delta["sample_vs_step"],
            "delta_amortized": delta["amortized"],
            "delta_target": DELTA_TARGET,
            "delta_target_met": bool(met),
            "n": n_max,
        },
    )
