"""Conditioning of a robot's GIM at the neutral, given or random configurations."""

from __future__ import annotations

import argparse

from gimwatch.analysis import analyze_configuration
from gimwatch.cli._format import non_negative_int, positive_int, table
from gimwatch.errors import InputError
from gimwatch.results import to_json
from gimwatch.robots import DATA_NV_LIMIT, load_robot, neutral_configuration, random_configurations

NAME = "analyze"
#: More configurations than this would print a table nobody reads; use ``survey``.
MAX_RANDOM = 100_000
HELP = "conditioning of M(q): kappa, diagonal ratio, pivot ratios, spectrum"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF path, or an example-robot-data name")
    parser.add_argument(
        "--q",
        type=float,
        nargs="+",
        metavar="Q",
        help="configuration (nq numbers); default: neutral",
    )
    parser.add_argument(
        "--random",
        type=positive_int,
        metavar="K",
        help="analyse K random configurations within the joint limits",
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the random draws")
    parser.add_argument("--floating", action="store_true", help="add a free-flyer base")
    parser.add_argument("--json", action="store_true", help="print JSON instead of a table")


def run(args: argparse.Namespace) -> int:
    """Analyse and print."""
    if args.q is not None and args.random is not None:
        raise InputError("--q and --random", "used one at a time", "both")
    if args.random is not None and args.random > MAX_RANDOM:
        raise InputError("--random", f"at most {MAX_RANDOM}", args.random)
    robot = load_robot(args.robot, floating=args.floating, max_nv=DATA_NV_LIMIT)
    if args.random is not None:
        configurations = random_configurations(robot, args.random, seed=args.seed)
    elif args.q is not None:
        if len(args.q) != robot.nq:
            raise InputError("--q", f"{robot.nq} numbers for {robot.name}", len(args.q))
        configurations = [args.q]
    else:
        configurations = [neutral_configuration(robot)]
    data = robot.new_data()
    results = [analyze_configuration(robot, q, data=data) for q in configurations]
    if args.json:
        records = [r.to_dict() for r in results]
        print(to_json(records[0] if len(records) == 1 else records))
        return 0
    print(f"{robot.name}: nv = {robot.nv}, {'floating' if robot.floating else 'fixed'} base")
    headers = [
        "config",
        "kappa",
        "delta",
        "pivot fwd",
        "pivot bwd",
        "lambda_min",
        "lambda_max",
        "max diag",
        "min diag",
    ]
    rows = [
        [
            i,
            r.kappa,
            r.diagonal_ratio,
            r.pivot_ratio_forward,
            r.pivot_ratio_backward,
            r.lambda_min,
            r.lambda_max,
            r.max_diagonal_dof,
            r.min_diagonal_dof,
        ]
        for i, r in enumerate(results)
    ]
    print(table(headers, rows))
    return 0
