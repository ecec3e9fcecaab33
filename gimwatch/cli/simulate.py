"""Simulate a scene file with the GIM watch alongside and write a results folder."""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from gimwatch.cli._progress import ProgressBar
from gimwatch.cli._signals import LATCH
from gimwatch.output.folders import Reservation
from gimwatch.simulation.backends import BACKENDS
from gimwatch.simulation.bundled_scenes import bundled_scenes
from gimwatch.simulation.results_folder import summarize, write_simulation
from gimwatch.simulation.scene import load_scene
from gimwatch.simulation.simulate import Simulation

NAME = "simulate"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "scene",
        help=f"scene file (TOML), or a bundled scene named without a path "
        f"({', '.join(bundled_scenes())}); the format: docs/scenes.md",
    )
    parser.add_argument(
        "-o", "--output", help="results folder (default: results/<scene name> next to the cwd)"
    )
    parser.add_argument(
        "--backend",
        choices=tuple(BACKENDS),
        help="dynamics backend instead of the scene's [dynamics] backend (denoc: the O(n) path "
        "for long fixed-base chains; chosen anyway above nv = 400)",
    )


def _summary_lines(trajectory) -> list[str]:
    """The run's summary for stdout: status, cost, drift, watch extremes, estimator quality."""
    summary = summarize(trajectory)
    lines = [
        f"{trajectory.robot}: {trajectory.status}, t = {summary['simulated_time_s']:.4g} s, "
        f"{trajectory.steps} steps, {trajectory.rhs_evaluations} RHS evaluations, "
        f"{trajectory.wall_time_s:.3g} s wall",
    ]
    if summary["energy_drift_relative"] is not None:
        lines.append(f"relative energy drift: {summary['energy_drift_relative']:.3g}")
    for name, value in summary["watch_maxima"].items():
        if name == "rcond":  # a reciprocal condition number: the smallest is the worst
            lines.append(f"min rcond: {float(trajectory.watch['watch_rcond'].min()):.6g}")
        else:
            lines.append(f"max {name}: {value:.6g}")
    if summary.get("kappa_tracked_fallbacks"):
        counts = summary["kappa_tracked_fallbacks"]
        lines.append("kappa_tracked samples: " + ", ".join(f"{k} {n}" for k, n in counts.items()))
    quality = summary["estimator_quality"]
    if isinstance(quality, dict):
        lines.append(
            f"estimator: alpha = {quality['alpha']:.4g}, Pearson(log) = "
            f"{quality['pearson_log']:.3f}, Spearman = {quality['spearman']:.3f}, median rel. "
            f"error = {quality['median_relative_error']:.3g}, max = "
            f"{quality['max_relative_error']:.3g}"
        )
    return lines


def run(args: argparse.Namespace) -> int:
    """Validate, simulate, write; report the status on stderr and a summary on stdout."""
    output = Path(args.output) if args.output else Path("results") / Path(args.scene).stem
    # Pinocchio and compiled (numba) code run from here on: a signal is noted and acted on
    # at safe points (here, and between integrator steps)
    with LATCH.deferred("hard"):
        scene = load_scene(args.scene)
        if args.backend is not None:
            scene = dataclasses.replace(scene, backend=args.backend)
        simulation = Simulation(scene)  # every error that needs the robot is raised here
    LATCH.check()
    with Reservation(output):  # refused (another writer, not ours) before the work
        with LATCH.deferred("hard"):
            bar = ProgressBar(f"{simulation.robot.name}")
            try:
                trajectory = simulation.run(progress=LATCH.checking(bar))
            finally:
                bar.close()
        with LATCH.deferred("soft"):  # a first signal lets the write complete
            folder = write_simulation(trajectory, output)
    for alarm in trajectory.alarms:
        print(
            f"gimwatch: warning: {alarm.metric} = {alarm.value:.4g} > {alarm.threshold:.4g} "
            f"at t = {alarm.time_s:.4g} s",
            file=sys.stderr,
        )
    print("\n".join(_summary_lines(trajectory)))
    print(f"wrote {folder}", file=sys.stderr)
    if trajectory.status == "interrupted" or LATCH.signum is not None:
        print("gimwatch: interrupted; results so far were written", file=sys.stderr)
        return LATCH.exit_status
    if trajectory.status in ("diverged", "failed"):
        print(
            f"gimwatch: error: {trajectory.message}; results so far were written", file=sys.stderr
        )
        return 1
    return 0
