"""Why κ is what it is at a configuration: the λmin and λmax modes and the ranked sensitivities."""

from __future__ import annotations

import argparse

from gimwatch.cli._format import positive_int, table
from gimwatch.cli._records import json_text
from gimwatch.explain.modes import GimModes, gim_modes
from gimwatch.explain.sensitivity import METRICS as SENSITIVITY_METRICS
from gimwatch.explain.sensitivity import KappaSensitivities, kappa_sensitivities
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot, neutral_configuration

NAME = "explain"
#: Joints and bodies listed per mode in the text output.
SHOWN = 3


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF or MJCF path, or an example-robot-data name")
    parser.add_argument(
        "--q",
        type=float,
        nargs="+",
        metavar="Q",
        help="configuration: nq numbers, a continuous joint by its angle (rad); default: neutral",
    )
    parser.add_argument("--floating", action="store_true", help="add a free-flyer base")
    parser.add_argument(
        "--top", type=positive_int, default=10, metavar="K", help="sensitivities listed"
    )
    parser.add_argument("--json", action="store_true", help="print JSON (every parameter)")
    parser.add_argument(
        "--metric",
        choices=SENSITIVITY_METRICS,
        default="kappa",
        help="explain kappa (of M) or kappa_equilibrated (of D^-1/2 M D^-1/2, the digits a "
        "Cholesky solve loses, in any units)",
    )


def mode_lines(modes: GimModes) -> list[str]:
    """The two modes in a few lines: joints by participation, bodies by energy share."""
    lines = []
    for label, mode in (("lambda_min", modes.lowest), ("lambda_max", modes.highest)):
        joints = ", ".join(f"{n} {p:.0%}" for n, p in mode.joints[:SHOWN])
        bodies = ", ".join(f"{n} {s:.0%}" for n, s in mode.bodies[:SHOWN])
        lines.append(f"{label} = {mode.eigenvalue:.6g}: moves {joints}; loads {bodies}")
        if mode.armature_share > 0:
            lines[-1] += f"; armature {mode.armature_share:.0%}"
    return lines


def sensitivity_table(result: KappaSensitivities, top: int) -> str:
    """The ``top`` sensitivities, ranked, as an aligned table."""
    headers = ["owner", "parameter", "value", "unit", "dkappa/dp", "elasticity"]
    rows = [
        [s.owner, s.parameter, s.value, s.unit, s.dkappa, s.elasticity]
        for s in result.sensitivities[:top]
    ]
    return table(headers, rows)


def run(args: argparse.Namespace) -> int:
    """Explain and print."""
    robot = load_robot(args.robot, floating=args.floating, max_nv=DATA_NV_LIMIT)
    q = (
        neutral_configuration(robot)
        if args.q is None
        else user_configuration(robot, args.q, key="--q")
    )
    modes = gim_modes(robot, q, metric=args.metric)
    result = kappa_sensitivities(robot, q, metric=args.metric)
    if args.json:
        print(json_text({"modes": modes.to_dict(), "sensitivities": result.to_dict()}))
        return 0
    print(f"{robot.name}: nv = {robot.nv}, {args.metric} = {result.kappa:.6g}")
    for line in mode_lines(modes):
        print(line)
    if result.clustered:
        print(
            f"note: lambda_min x{result.clustered_min}, lambda_max x{result.clustered_max} "
            "(clustered): derivatives are one-sided, as p increases"
        )
    print("d log kappa / d log p, largest first (dkappa/dp in 1/unit):")
    print(sensitivity_table(result, args.top))
    return 0
