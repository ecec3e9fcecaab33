"""What the GIM watch costs per integration step: no watch, δ, αδ and κ.

The chain of n rods swings under gravity with fixed-step RK4 (4 ABA calls per step); the
watch runs at the samples only (every ``steps_per_sample`` steps). For each watch the
benchmark reports

* ``step_us`` / ``overhead_vs_bare``: whole runs timed (median of ``repeats``), time per
  step and its excess over the bare run (noisy on a shared machine: the difference of two
  run times);
* ``per_sample_us``: one :meth:`Watch.sample` timed alone on the run's configurations
  (median of ``repeats`` passes), and ``amortized_overhead`` = per_sample_us /
  (steps_per_sample x bare step_us), the watch's share of a bare step;
* ``aba_call_us``: one ``pinocchio.aba`` call, for scale.
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin

from gimwatch.robots import load_robot
from gimwatch.scene import parse_scene
from gimwatch.simulate import Simulation
from gimwatch.watch import Watch

__all__ = ["COLUMNS", "WATCHES", "run"]

#: Watch configurations: label -> metrics.
WATCHES = {
    "none": [],
    "delta": ["diagonal_ratio"],
    "alpha_delta": ["scaled_diagonal_ratio"],
    "kappa": ["kappa"],
}
COLUMNS = (
    "n",
    "watch",
    "steps",
    "samples",
    "step_us",
    "overhead_vs_bare",
    "per_sample_us",
    "amortized_overhead",
    "aba_call_us",
)


def _scene(n: int, metrics: list[str], steps: int, dt: float, steps_per_sample: int):
    return parse_scene(
        {
            "robot": f"chain:{n}",
            "duration": steps * dt,
            "sample": steps_per_sample * dt,
            "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
            "integrator": {"method": "RK4", "dt": dt},
            "watch": {"metrics": metrics},
        },
        source=f"<bench chain_{n}>",
    )


def _time_run(scene, repeats: int):
    times = []
    for _ in range(repeats):
        simulation = Simulation(scene)
        start = time.perf_counter()
        trajectory = simulation.run()
        times.append(time.perf_counter() - start)
    return float(np.median(times)), trajectory


def _time_samples(robot, metrics: list[str], qs: np.ndarray, repeats: int) -> float:
    if not metrics:
        return 0.0
    passes = []
    for _ in range(repeats):
        watch = Watch(robot, tuple(metrics))
        start = time.perf_counter()
        for k, q in enumerate(qs):
            watch.sample(float(k), q)
        passes.append((time.perf_counter() - start) / len(qs))
    return float(np.median(passes)) * 1e6


def _aba_call_us(n: int, calls: int = 2000) -> float:
    robot = load_robot(f"chain:{n}")
    model, data = robot.model, robot.new_data()
    rng = np.random.default_rng(0)
    q, v, tau = rng.standard_normal((3, n))
    start = time.perf_counter()
    for _ in range(calls):
        pin.aba(model, data, q, v, tau)
    return (time.perf_counter() - start) / calls * 1e6


def run(
    *,
    lengths: tuple[int, ...] = (4, 10, 20),
    steps: int = 1000,
    dt: float = 1e-3,
    steps_per_sample: int = 10,
    repeats: int = 3,
) -> list[dict]:
    """Measure and return one row per (n, watch) with the fields of :data:`COLUMNS`."""
    rows = []
    for n in lengths:
        aba_us = _aba_call_us(n)
        robot = load_robot(f"chain:{n}")
        bare_step = configurations = None
        for label, metrics in WATCHES.items():
            wall, trajectory = _time_run(_scene(n, metrics, steps, dt, steps_per_sample), repeats)
            step_us = wall / trajectory.steps * 1e6
            if bare_step is None:
                bare_step, configurations = step_us, trajectory.q
            per_sample = _time_samples(robot, metrics, configurations, repeats)
            rows.append(
                {
                    "n": n,
                    "watch": label,
                    "steps": trajectory.steps,
                    "samples": int(trajectory.t.size),
                    "step_us": step_us,
                    "overhead_vs_bare": step_us / bare_step - 1.0,
                    "per_sample_us": per_sample,
                    "amortized_overhead": per_sample / (steps_per_sample * bare_step),
                    "aba_call_us": aba_us,
                }
            )
    return rows
