"""Will it explode? The largest stable timestep of each robot under its servos and integrator."""

from __future__ import annotations

import argparse
import sys

import numpy as np

from gimwatch.cli._batch import expand_specs
from gimwatch.cli._format import non_negative_int, positive_int, table
from gimwatch.cli._records import json_text
from gimwatch.errors import GimwatchError, InputError
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.stability.analysis import stability
from gimwatch.stability.step_maps import INTEGRATORS

NAME = "stability"
MAX_RANDOM = 10_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "robots",
        nargs="+",
        metavar="ROBOT",
        help="an MJCF file (its own actuators, timestep and integrator), a URDF, chain:N or "
        "example-robot-data name (with --kp/--kd), or a folder of files",
    )
    parser.add_argument(
        "--integrator",
        nargs="+",
        metavar="NAME",
        help=f"one or more of {', '.join(INTEGRATORS)} (default: the model's own; Euler "
        "without one)",
    )
    parser.add_argument(
        "--timestep", type=float, metavar="H", help="timestep judged, s (default: the model's)"
    )
    parser.add_argument("--kp", type=float, nargs="+", help="servo stiffness: one or one per joint")
    parser.add_argument("--kd", type=float, nargs="+", help="servo damping: one or one per joint")
    parser.add_argument("--no-gravity", action="store_true", help="leave gravity's stiffness out")
    parser.add_argument("--keyframe", metavar="NAME", help="MJCF: hold this keyframe")
    parser.add_argument("--q", type=float, nargs="+", metavar="Q", help="hold this configuration")
    parser.add_argument(
        "--random", type=positive_int, metavar="K", help="hold K random configurations"
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the draws")
    parser.add_argument(
        "--trajectory",
        metavar="CSV",
        help="hold every row of a CSV of q (as map --trajectory: nq columns in Pinocchio's "
        "q order, an optional header and t column)",
    )
    parser.add_argument("--json", action="store_true", help="print JSON rows")


def _configurations(robot, args):
    if args.q is not None:
        return user_configuration(robot, args.q, key="--q")[None, :]
    if args.random is not None:
        return random_configurations(robot, args.random, seed=args.seed)
    if args.trajectory is not None:
        from gimwatch.explain.trajectory import read_trajectory_csv
        from gimwatch.output.figures import joint_coordinate_units

        names = joint_coordinate_units(robot.model)[0]
        return read_trajectory_csv(args.trajectory, names)[1]
    return None


def _rows(spec: str, args: argparse.Namespace):
    robot = load_robot(spec, floating=False, max_nv=DATA_NV_LIMIT)
    return stability(
        robot,
        _configurations(robot, args),
        integrators=args.integrator,
        timestep_s=args.timestep,
        gravity=not args.no_gravity,
        kp=args.kp,
        kd=args.kd,
        keyframe=args.keyframe,
    )


def run(args: argparse.Namespace) -> int:
    """One row per robot, configuration and integrator; exit 1 if any is unstable."""
    chosen = (args.q, args.random, args.keyframe, args.trajectory)
    if sum(x is not None for x in chosen) > 1:
        raise InputError(
            "--q, --random, --keyframe and --trajectory", "used one at a time", "several"
        )
    if args.random is not None and args.random > MAX_RANDOM:
        raise InputError("--random", f"at most {MAX_RANDOM}", args.random)
    for name in args.integrator or ():
        if name not in INTEGRATORS:
            raise InputError("--integrator", f"one of {', '.join(INTEGRATORS)}", name)
    if args.timestep is not None and not (np.isfinite(args.timestep) and args.timestep > 0):
        raise InputError("--timestep", "a finite number of seconds > 0", args.timestep)
    specs = expand_specs(args.robots)
    results: list[tuple[str, list, str]] = []
    for spec in specs:
        try:
            results.append((spec, _rows(spec, args), ""))
        except GimwatchError as exc:
            if len(specs) == 1:
                raise
            results.append((spec, [], str(exc)))
    _print(results, args)
    if any(reason for _, _, reason in results):
        return 2
    return 1 if any(not r.stable for _, rows, _ in results for r in rows) else 0


def _h(value: float) -> str:
    return "inf" if not np.isfinite(value) else f"{value:.4g}"


def _print(results, args: argparse.Namespace) -> None:
    if args.json:
        records_json: list[dict] = []
        for spec, records, reason in results:
            if reason:
                records_json.append({"robot": spec, "status": "refused", "reason": reason})
            records_json.extend(r.to_dict() for r in records)
        print(json_text({"rows": records_json}))
        return
    headers = [
        "robot",
        "config",
        "integrator",
        "h*_s",
        "timestep_s",
        "h/h*",
        "verdict",
        "critical_dof",
        "limited_by",
    ]
    rows: list[list[object]] = []
    notes: dict[str, tuple[str, ...]] = {}
    for spec, records, reason in results:
        if reason:
            print(f"{spec}: refused: {reason}", file=sys.stderr)
        for r in records:
            verdict = "stable" if r.stable else "UNSTABLE"
            rows.append(
                [
                    r.robot,
                    r.config,
                    r.integrator,
                    _h(r.max_stable_timestep_s),
                    r.timestep_s,
                    r.margin,
                    verdict,
                    r.critical_dof,
                    r.limited_by,
                ]
            )
            if r.not_modelled:
                notes[r.robot] = r.not_modelled
    print(table(headers, rows))
    for robot, items in notes.items():
        print(f"{robot}: not modelled: {', '.join(items)}")
