"""Cross-check DeNOC (numpy + yourdfpy) against Pinocchio: GIM, τ, q̈ and UDUᵀ pivots.

ROBOT is chain:N, a URDF path, an example-robot-data name, or ``all`` (every
example-robot-data robot; those that cannot be loaded are skipped with the reason on
stderr). Exit status 1 when any robot is beyond the tolerance.
"""

from __future__ import annotations

import argparse
import sys

from gimwatch.cli._format import add_mjcf_arguments, non_negative_int, positive_int, table
from gimwatch.cli._records import add_output_arguments, csv_text, json_text
from gimwatch.crosscheck import (
    DEFAULT_TOLERANCE,
    CrossCheckResult,
    check_tolerance,
    crosscheck_robot,
)
from gimwatch.errors import RobotError
from gimwatch.model.robots import example_robot_names, load_robot

NAME = "crosscheck"
HELP = "compare DeNOC with Pinocchio (crba, rnea, aba, cholesky) at random states"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robots", nargs="+", metavar="ROBOT", help="robot specs, or 'all'")
    parser.add_argument("--samples", type=positive_int, default=10, help="random states")
    parser.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of the random states"
    )
    parser.add_argument("--floating", action="store_true", help="add a free-flyer base")
    parser.add_argument(
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        help="largest relative error that passes",
    )
    parser.add_argument(
        "--peer",
        choices=("mujoco",),
        default=None,
        help="also compare MuJoCo's mj_fullM with Pinocchio's crba (MJCF robots: always)",
    )
    add_mjcf_arguments(parser)
    add_output_arguments(parser, what="robots")


#: ``--csv`` columns, one row per robot (the fields of :class:`CrossCheckResult`).
CSV_COLUMNS = tuple(CrossCheckResult.__dataclass_fields__)


def _print(results: list[CrossCheckResult], args: argparse.Namespace) -> None:
    records = [r.to_dict() for r in results]
    if args.json:
        print(json_text({"tolerance": args.tolerance, "robots": records}))
        return
    if args.csv:
        print(csv_text(records, CSV_COLUMNS))
        return
    headers = ["robot", "base", "nv", "GIM", "diag", "tau", "qdd", "qdd bwd", "pivots"]
    fields = [
        "gim_rel_err",
        "gim_diagonal_rel_err",
        "tau_rel_err",
        "qdd_rel_err",
        "qdd_backward_err",
        "pivots_rel_err",
    ]
    if any(r.mujoco_gim_rel_err is not None for r in results):
        headers.append("M mujoco")
        fields.append("mujoco_gim_rel_err")
    headers.append("kappa")
    fields.append("kappa_max")
    rows = [
        [
            r.robot + ("" if r.passed else "  FAIL"),
            "floating" if r.floating else "fixed",
            r.nv,
            *("n/a" if getattr(r, f) is None else getattr(r, f) for f in fields),
        ]
        for r in results
    ]
    print(table(headers, rows))
    for r in results:
        if r.note:
            print(f"{r.robot}: {r.note}")
    failed = sum(not r.passed for r in results)
    print(f"{len(results) - failed}/{len(results)} passed (tolerance {results[0].tolerance:g})")


def run(args: argparse.Namespace) -> int:
    """Cross-check each robot and print the worst errors."""
    check_tolerance(args.tolerance, "--tolerance")
    everything = "all" in args.robots
    specs = list(example_robot_names()) if everything else args.robots
    # Load every named robot first, so that bad input fails with one line before any work.
    mjcf = {"body": args.body, "armature": not args.no_armature}
    robots = [] if everything else [load_robot(s, floating=args.floating, **mjcf) for s in specs]
    results: list[CrossCheckResult] = []
    try:
        for i, spec in enumerate(specs, 1):
            if len(specs) > 1:
                print(f"crosscheck: [{i}/{len(specs)}] {spec}", file=sys.stderr)
            if everything:
                try:
                    robot = load_robot(spec, floating=args.floating)
                except RobotError as exc:
                    print(f"crosscheck: skipped {spec}: {exc.problem}", file=sys.stderr)
                    continue
            else:
                robot = robots[i - 1]
            results.append(
                crosscheck_robot(
                    robot,
                    samples=args.samples,
                    seed=args.seed,
                    tolerance=args.tolerance,
                    peer=args.peer,
                )
            )
    except KeyboardInterrupt:
        if results:
            _print(results, args)
        raise
    if results:
        _print(results, args)
    return 0 if all(r.passed for r in results) else 1
