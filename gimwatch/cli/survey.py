"""Survey robots: κ, δ, pivot ratios over random configurations; report.md, JSON, CSV, plots."""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

from gimwatch.cli._batch import expand_specs
from gimwatch.cli._format import (
    add_base_arguments,
    check_workers,
    non_negative_int,
    positive_int,
    table,
)
from gimwatch.cli._signals import LATCH
from gimwatch.errors import GimwatchError, InputError
from gimwatch.output.folders import Reservation
from gimwatch.simulation.scene_integrator import DEFAULT_MAX_STEPS
from gimwatch.survey.report import write_survey
from gimwatch.survey.run import run_survey
from gimwatch.survey.trajectory import TrajectorySettings

NAME = "survey"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "robots",
        nargs="+",
        metavar="ROBOT",
        help="chain:N, a URDF/MJCF path or a folder of them, an example-robot-data name, or "
        "'all' (every such robot); a refused robot is reported and the exit status is 2",
    )
    parser.add_argument(
        "--samples", type=positive_int, default=200, metavar="K", help="random configurations"
    )
    parser.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of the random configurations"
    )
    add_base_arguments(parser)
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on Dask: 'local' (a LocalCluster) or a scheduler address (tcp://host:port)",
    )
    parser.add_argument(
        "--workers",
        type=positive_int,
        metavar="N",
        help="local processes when no --scheduler; 1: in this process (default: this process "
        "for small surveys, every core for larger ones)",
    )
    parser.add_argument(
        "--chunk-size", type=positive_int, default=50, metavar="N", help="samples per task"
    )
    parser.add_argument(
        "--trajectory",
        action="store_true",
        help="also simulate short runs falling under gravity and watch kappa and delta along them",
    )
    parser.add_argument(
        "--duration",
        type=_positive_seconds,
        default=TrajectorySettings.duration_s,
        metavar="S",
        help="length of each simulated run in seconds (with --trajectory)",
    )
    parser.add_argument(
        "--runs",
        type=positive_int,
        default=TrajectorySettings.count,
        metavar="N",
        help="simulated runs per robot, from random samples 1..N (with --trajectory)",
    )
    parser.add_argument("-o", "--output", default="survey-output", help="output folder")


def _positive_seconds(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"must be a positive number of seconds, got {text!r}")
    return value


def _check_budgets(args: argparse.Namespace) -> None:
    """Workers within the cores, trajectories within the step budget, before any work."""
    if args.scheduler is None:
        check_workers(args.workers)
    dt = TrajectorySettings.dt_s
    if args.trajectory and args.duration / dt > DEFAULT_MAX_STEPS:
        raise InputError(
            "--duration",
            f"at most {DEFAULT_MAX_STEPS * dt:g} s (the step budget of {DEFAULT_MAX_STEPS} "
            f"steps of {dt:g} s)",
            args.duration,
        )


def run(args: argparse.Namespace) -> int:
    """Survey, write the files, print the summary table."""
    _check_budgets(args)
    output = Path(args.output)
    with Reservation(output):  # refused (another writer, not ours) before the work
        result, wall_time_s = _survey(args)
        if not result.robots and result.failures and not result.interrupted:
            raise GimwatchError(result.failures[0].reason)  # nothing to report: nothing written
        with LATCH.deferred("soft"):  # a first signal lets the write complete
            report = write_survey(result, output, wall_time_s=wall_time_s)
    rows = [
        [
            r.name,
            r.nv,
            r.samples,
            r.quantiles["kappa"]["median"],
            r.quantiles["kappa"]["max"],
            r.pearson_log,
            r.spearman,
            r.alpha_delta_rel_error_median,
        ]
        + (
            []
            if r.trajectories is None
            else [r.trajectories.pearson_log_median, r.trajectories.alpha_delta_rel_error_median]
        )
        for r in result.robots
    ]
    headers = ["robot", "nv", "samples", "kappa med", "kappa max", "pearson", "spearman", "ad err"]
    if args.trajectory:
        headers += ["run pearson", "run ad err"]
    if rows:
        print(table(headers, rows))
    named = set(expand_specs(args.robots)) - {"all"}
    refused = [f for f in result.failures if f.stage == "load" and f.spec in named]
    for failure in result.failures:
        what = "refused" if failure in refused else "not surveyed"
        print(f"{what}: {failure.spec}: {failure.reason}")
    print(
        f"wrote {report} ({len(result.robots)} robots, {len(result.failures)} failed, "
        f"{wall_time_s:.1f} s)",
        file=sys.stderr,
    )
    if result.interrupted or LATCH.signum is not None:
        print("gimwatch: interrupted; partial results written", file=sys.stderr)
        return LATCH.exit_status
    return 2 if refused else 0  # a robot named on the command line was bad input


def _survey(args: argparse.Namespace):
    """Run the survey the arguments ask for; return it and its wall time in seconds."""
    from tqdm import tqdm

    trajectories = None
    if args.trajectory:
        dt = TrajectorySettings.dt_s  # samples fall on RK4 steps: a whole number of dt
        sample_s = max(1, round(min(TrajectorySettings.sample_s, args.duration / 10) / dt)) * dt
        trajectories = TrajectorySettings(
            count=args.runs, duration_s=args.duration, sample_s=sample_s
        )
    start = time.perf_counter()
    # disable=None: the bar shows on a terminal only, so logs and pipes get no carriage returns
    with tqdm(
        total=None, unit="chunk", file=sys.stderr, desc="survey", leave=False, disable=None
    ) as bar:

        def progress(finished: int, total: int) -> None:
            bar.total = total
            bar.update(finished - bar.n)

        result = run_survey(
            expand_specs(args.robots),
            samples=args.samples,
            seed=args.seed,
            floating=args.floating,
            chunk_size=args.chunk_size,
            workers=args.workers,
            scheduler=args.scheduler,
            progress=progress,
            trajectories=trajectories,
        )
    return result, time.perf_counter() - start
