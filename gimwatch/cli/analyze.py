"""Conditioning of a robot's GIM at the neutral, given or random configurations."""

from __future__ import annotations

import argparse
import math
import sys

from gimwatch.cli._format import non_negative_int, positive_int, table
from gimwatch.cli._records import add_output_arguments, csv_text, json_text
from gimwatch.errors import InputError
from gimwatch.metrics.dense_analysis import analyze_configuration
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import (
    DATA_NV_LIMIT,
    check_random_budget,
    load_robot,
    neutral_configuration,
    parse_chain_spec,
    random_configurations,
)

NAME = "analyze"
#: More configurations than this would print a table nobody reads; use ``survey``.
MAX_RANDOM = 100_000
#: The O(n) path's largest chain: diag, pivots and κ stay O(n) (about 1 kB per link).
LINEAR_NV_LIMIT = 200_000
HELP = "conditioning of M(q): kappa, diagonal ratio, pivot ratios, spectrum"
#: ``--csv`` columns, one row per configuration (vectors ``;``-separated).
CSV_COLUMNS = (
    "config",
    "robot",
    "nv",
    "method",
    "kappa",
    "diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "lambda_min",
    "lambda_max",
    "max_diagonal_dof",
    "min_diagonal_dof",
    "q",
    "eigenvalues",
    "diagonal",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF path, or an example-robot-data name")
    parser.add_argument(
        "--q",
        type=float,
        nargs="+",
        metavar="Q",
        help="configuration: nq numbers, a continuous joint by its angle (rad); default: neutral",
    )
    parser.add_argument(
        "--random",
        type=positive_int,
        metavar="K",
        help="analyse K random configurations within the joint limits",
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the random draws")
    parser.add_argument("--floating", action="store_true", help="add a free-flyer base")
    add_output_arguments(parser, what="configurations")
    parser.add_argument(
        "--backend",
        choices=("auto", "crba", "denoc"),
        default="auto",
        help="crba: dense M from Pinocchio; denoc: the O(n) path (no Data, no dense M; fixed "
        f"base); auto: denoc above nv = {DATA_NV_LIMIT}, where Pinocchio's Data needs GBs",
    )
    parser.add_argument(
        "--metrics",
        help="comma-separated subset of kappa,diagonal_ratio,pivot_ratio_backward to compute "
        "on the O(n) path (default: all three)",
    )


def _configurations(args: argparse.Namespace, nq: int, neutral, draw, robot=None) -> list:
    if args.random is not None:
        check_random_budget(args.random, nq)  # before anything is drawn
        return list(draw(args.random))
    if args.q is not None:
        if robot is not None and robot.nq != robot.nv:  # continuous joints by angle, unit checks
            if not all(math.isfinite(x) for x in args.q):
                raise InputError("q", "finite", args.q)
            return [user_configuration(robot, args.q, key="--q")]
        if len(args.q) != nq:
            raise InputError("--q", f"{nq} numbers for {args.robot}", len(args.q))
        return [args.q]
    return [neutral]


def _run_linear(args: argparse.Namespace, chain, announce: bool) -> list:
    """The O(n) DeNOC path: generated chains never build a URDF or a Pinocchio model."""
    from gimwatch.denoc import DenocModel
    from gimwatch.metrics.linear_analysis import (
        LINEAR_METRICS,
        analyze_linear,
        chain_configurations,
    )

    if args.floating:
        raise InputError("--floating", "left out with --backend denoc (fixed bases only)", True)
    metrics = LINEAR_METRICS if args.metrics is None else tuple(args.metrics.split(","))
    if chain is not None:
        if chain.n > LINEAR_NV_LIMIT:
            raise InputError("the N of chain:N", f"at most {LINEAR_NV_LIMIT}", chain.n)
        model, name = DenocModel.from_chain(chain), chain.name
        configurations = _configurations(
            args,
            chain.n,
            [0.0] * chain.n,
            lambda k: chain_configurations(chain, k, seed=args.seed),
        )
    else:
        robot = load_robot(args.robot)
        model = DenocModel.from_urdf(
            robot.urdf_xml, source=robot.source, joint_order=robot.joint_names
        )
        name = robot.name
        configurations = _configurations(
            args,
            robot.nq,
            neutral_configuration(robot),
            lambda k: random_configurations(robot, k, seed=args.seed),
            robot,
        )
    if announce:
        print(
            f"gimwatch: {name} has nv = {model.nv} > {DATA_NV_LIMIT}: using the O(n) DeNOC "
            "path (Pinocchio's Data would need GBs)",
            file=sys.stderr,
        )
    return [
        analyze_linear(model, q, name=name, metrics=metrics, seed=args.seed) for q in configurations
    ]


def run(args: argparse.Namespace) -> int:
    """Analyse and print."""
    if args.q is not None and args.random is not None:
        raise InputError("--q and --random", "used one at a time", "both")
    if args.random is not None and args.random > MAX_RANDOM:
        raise InputError("--random", f"at most {MAX_RANDOM}", args.random)
    chain = parse_chain_spec(args.robot)
    large = chain is not None and not args.floating and chain.n > DATA_NV_LIMIT
    linear = args.backend == "denoc" or (args.backend == "auto" and large)
    if args.metrics is not None and not linear:
        raise InputError("--metrics", "used with the O(n) path (--backend denoc)", args.metrics)
    if linear:
        results = _run_linear(args, chain, announce=args.backend == "auto")
    else:
        robot = load_robot(args.robot, floating=args.floating, max_nv=DATA_NV_LIMIT)
        configurations = _configurations(
            args,
            robot.nq,
            neutral_configuration(robot),
            lambda k: random_configurations(robot, k, seed=args.seed),
            robot,
        )
        data = robot.new_data()
        results = [analyze_configuration(robot, q, data=data) for q in configurations]
    first = results[0]
    base = "floating" if args.floating else "fixed"
    records = [{"config": i, **r.to_dict()} for i, r in enumerate(results)]
    if args.json:
        header = {"robot": first.robot, "nv": first.nv, "base": base, "method": first.method}
        print(json_text({**header, "configurations": records}))
        return 0
    if args.csv:
        print(csv_text(records, CSV_COLUMNS))
        return 0
    print(f"{first.robot}: nv = {first.nv}, {base} base, method {first.method}")
    # the registry's names, as in --json and --csv
    headers = [
        "config",
        "kappa",
        "diagonal_ratio",
        "pivot_ratio_forward",
        "pivot_ratio_backward",
        "lambda_min",
        "lambda_max",
        "max_diagonal_dof",
        "min_diagonal_dof",
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
