"""Where κ is large: κ, δ or any scalar metric over two joints, or along a trajectory file."""

from __future__ import annotations

import argparse
import sys

import numpy as np
from tqdm import tqdm

from gimwatch.cli._format import check_workers, positive_int
from gimwatch.errors import InputError
from gimwatch.explain.map_files import write_map, write_trajectory_metrics
from gimwatch.explain.maps import MAX_GRID, ConditioningMap, conditioning_map
from gimwatch.explain.trajectory import TrajectoryMetrics, trajectory_metrics
from gimwatch.metrics.analyze import RobotLike, robot_for_path
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robot_spec import RobotSpec

NAME = "map"
#: Library parameters named otherwise on this command line (see `gimwatch.cli.parameter_options`).
PARAMETER_OPTIONS = {"path": "--trajectory"}


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF or MJCF path, or an example-robot-data name")
    parser.add_argument("--joints", nargs=2, metavar=("X", "Y"), help="the two joints to sweep")
    parser.add_argument(
        "--grid", type=positive_int, default=50, metavar="N", help=f"points per side (2-{MAX_GRID})"
    )
    parser.add_argument(
        "--range",
        type=float,
        nargs=4,
        metavar=("XLO", "XHI", "YLO", "YHI"),
        help="the joints' ranges (rad or m); default: their limits",
    )
    parser.add_argument(
        "--q", type=float, nargs="+", metavar="Q", help="the other joints' configuration (nq)"
    )
    parser.add_argument("--trajectory", metavar="CSV", help="a CSV of q, one row per sample")
    parser.add_argument(
        "--metrics", default="kappa,diagonal_ratio", help="comma-separated registry metrics"
    )
    parser.add_argument(
        "--backend",
        choices=("auto", "crba", "denoc"),
        default="auto",
        help="crba: dense M; denoc: the O(n) path; auto: denoc for chains beyond Pinocchio's Data",
    )
    parser.add_argument("--workers", type=positive_int, default=1, metavar="N", help="processes")
    parser.add_argument("--scheduler", metavar="ADDRESS", help="Dask: 'local' or tcp://host:port")
    parser.add_argument("-o", "--output", required=True, metavar="DIR", help="results folder")


def run(args: argparse.Namespace) -> int:
    """Map, write, print where the files are."""
    if (args.joints is None) == (args.trajectory is None):
        raise InputError("--joints and --trajectory", "given one at a time (exactly one)", None)
    if args.trajectory is not None and (args.range or args.q):
        raise InputError("--range and --q", "used with --joints only", "--trajectory")
    if args.scheduler is None:  # as survey: more processes than cores only add memory
        check_workers(args.workers)
    metrics = [m.strip() for m in args.metrics.split(",")]
    with tqdm(total=1.0, file=sys.stderr, desc="map", leave=False, disable=None) as bar:

        def progress(fraction: float) -> None:
            bar.update(fraction - bar.n)

        common = {
            "metrics": metrics,
            "backend": args.backend,
            "workers": args.workers,
            "scheduler": args.scheduler,
            "progress": progress,
        }
        robot: RobotLike = RobotSpec.parse(args.robot)  # parsed once, loaded at most once
        result: ConditioningMap | TrajectoryMetrics
        if args.trajectory is not None:
            result = trajectory_metrics(robot, args.trajectory, **common)
        else:
            q = None
            if args.q is not None:
                robot = robot_for_path(robot)
                q = user_configuration(robot, args.q, key="--q")
            ranges = None if args.range is None else [args.range[:2], args.range[2:]]
            result = conditioning_map(
                robot, args.joints, grid=args.grid, ranges=ranges, q=q, **common
            )
    if result.interrupted:
        print("gimwatch: interrupted: writing the part computed (NaN elsewhere)", file=sys.stderr)
    written = (
        write_map(result, args.output)
        if isinstance(result, ConditioningMap)
        else write_trajectory_metrics(result, args.output)
    )
    for metric, values in result.values.items():
        low, high = np.nanmin(values), np.nanmax(values)
        print(f"{metric}: {low:.6g} to {high:.6g}")
    print(f"wrote {written.parent}", file=sys.stderr)
    return 130 if result.interrupted else 0
