"""The least joint armature that brings κ under a target, or makes a timestep stable."""

from __future__ import annotations

import argparse

import numpy as np

from gimwatch.cli._format import non_negative_int, positive_int, table
from gimwatch.cli._records import json_text
from gimwatch.errors import InputError
from gimwatch.explain.armature import MAX_MATRIX_BYTES, max_configurations, minimal_armature
from gimwatch.joint_kinds import length_velocities
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.stability.step_maps import INTEGRATORS

NAME = "armature"
#: More configurations than this make each cutting-plane round slow; sample fewer.
MAX_SAMPLES = 100_000
#: Random configurations of the κ target when neither --q nor --samples is given.
DEFAULT_SAMPLES = 100


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF or MJCF path, or an example-robot-data name")
    goal = parser.add_mutually_exclusive_group(required=True)
    goal.add_argument("--target", type=float, metavar="KAPPA", help="the largest kappa allowed")
    goal.add_argument(
        "--timestep",
        type=float,
        metavar="H",
        help="a timestep (s) to make stable under the robot's servos and --integrator",
    )
    parser.add_argument(
        "--integrator",
        choices=tuple(INTEGRATORS),
        help="with --timestep: the integrator (default: the model's own; Euler without one)",
    )
    parser.add_argument(
        "--samples",
        type=positive_int,
        metavar="K",
        help=f"random configurations (default: {DEFAULT_SAMPLES} for --target; the keyframe "
        "or neutral configuration for --timestep)",
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the draws")
    parser.add_argument(
        "--q", type=float, nargs="+", metavar="Q", help="one configuration instead of random ones"
    )
    parser.add_argument(
        "--per-joint",
        action="store_true",
        help="one value per joint, least total (cutting planes); default: one uniform value",
    )
    parser.add_argument("--kp", type=float, nargs="+", help="--timestep: servo stiffness")
    parser.add_argument("--kd", type=float, nargs="+", help="--timestep: servo damping")
    parser.add_argument(
        "--no-gravity", action="store_true", help="--timestep: leave gravity's stiffness out"
    )
    parser.add_argument("--keyframe", metavar="NAME", help="--timestep, MJCF: hold this keyframe")
    parser.add_argument("--json", action="store_true", help="print JSON")


#: An armature below this fraction of the largest one is the float64 lift of the answer
#: (a relative 1e-9, see docs/guide/explain.md), not a rotor to add: printed "none".
NONE_NEEDED = 1e-6


def _shown(value: float, largest: float) -> float | str:
    return "none" if value <= NONE_NEEDED * largest else value


def _armature_units(model) -> list[str]:
    """The unit of each velocity coordinate's armature: kg·m² turning, kg sliding."""
    units = []
    for joint in model.joints[1:]:
        sliding = length_velocities(joint)  # the first `sliding` coordinates translate
        units += ["kg"] * sliding + ["kg*m^2"] * (joint.nv - sliding)
    return units


def _armature_rows(names, armature, model, *extra) -> list[list]:
    """Rows of (coordinate, armature or "none", unit, *extra columns)."""
    largest = max(armature) if len(armature) else 0.0
    units = _armature_units(model)
    return [
        [name, _shown(value, largest), unit, *more]
        for name, value, unit, *more in zip(names, armature, units, *extra, strict=True)
    ]


def run(args: argparse.Namespace) -> int:
    """Compute and print."""
    if args.samples is not None and args.samples > MAX_SAMPLES:
        raise InputError("--samples", f"at most {MAX_SAMPLES}", args.samples)
    if args.timestep is not None:
        return _timestep(args)
    for flag in ("integrator", "kp", "kd", "keyframe"):
        if getattr(args, flag) is not None:
            raise InputError(f"--{flag}", "given only with --timestep", getattr(args, flag))
    if not np.isfinite(args.target) or args.target <= 1.0:
        raise InputError("--target", "a number > 1 (κ ≥ 1 always)", args.target)
    robot = load_robot(args.robot, max_nv=DATA_NV_LIMIT)
    samples = args.samples or DEFAULT_SAMPLES
    if args.q is None:
        _check_budget(robot, samples)
    if args.q is not None:
        qs = user_configuration(robot, args.q, key="--q")[None, :]
    else:
        qs = random_configurations(robot, samples, seed=args.seed)
    plan = minimal_armature(robot, qs, args.target, per_joint=args.per_joint)
    if args.json:
        print(json_text(plan.to_dict()))
        return 0
    kind = "per joint (least total)" if plan.per_joint else "uniform"
    print(f"{robot.name}: target kappa {plan.target:g} over {len(qs)} configuration(s), {kind}")
    print(f"kappa max: {max(plan.kappa_before):.6g} -> {max(plan.kappa_after):.6g}")
    rows = _armature_rows(plan.dof_names, plan.armature, robot.model)
    print(table(["coordinate", "armature", "unit"], rows))
    gap = "" if not plan.per_joint else f" (least total >= {plan.lower_bound:.6g})"
    print(f"total {plan.total:.6g}{gap}")
    change = np.array(plan.qdd_change)
    print(
        f"q̈ under gravity changes by {np.median(change):.1%} (median), "
        f"{change.max():.1%} (max) over the configurations"
    )
    return 0


def _check_budget(robot, samples: int) -> None:
    """Refuse K configurations whose K nv × nv matrices exceed the budget, before drawing."""
    fits = max_configurations(robot.nv)
    if samples > fits:
        raise InputError(
            "--samples",
            f"at most {fits} for {robot.name} (nv = {robot.nv}: K nv x nv matrices within "
            f"the {MAX_MATRIX_BYTES >> 20} MiB budget)",
            samples,
        )


def _timestep(args: argparse.Namespace) -> int:
    from gimwatch.explain.timestep_armature import timestep_armature
    from gimwatch.stability.analysis import held_systems

    if not (np.isfinite(args.timestep) and args.timestep > 0):
        raise InputError("--timestep", "a finite number of seconds > 0", args.timestep)
    robot = load_robot(args.robot, floating=False, max_nv=DATA_NV_LIMIT)
    if args.q is not None and args.samples is not None:
        raise InputError("--q and --samples", "used one at a time", "both")
    qs = None
    if args.q is not None:
        qs = user_configuration(robot, args.q, key="--q")[None, :]
    elif args.samples is not None:
        _check_budget(robot, args.samples)
        qs = random_configurations(robot, args.samples, seed=args.seed)
    options = {"kp": args.kp, "kd": args.kd, "gravity": not args.no_gravity}
    integrator = args.integrator
    if integrator is None:
        _, _, servos = held_systems(robot, qs, keyframe=args.keyframe, **options)
        integrator = servos.integrator or "Euler"
    plan = timestep_armature(
        robot,
        args.timestep,
        integrator,
        qs,
        per_joint=args.per_joint,
        keyframe=args.keyframe,
        **options,
    )
    if args.json:
        print(json_text(plan.to_dict()))
        return 0
    kind = "per joint (least total)" if plan.per_joint else "uniform"
    count = len(plan.h_star_before_s)
    print(
        f"{robot.name}: {integrator} stable at {plan.timestep_s:g} s over {count} "
        f"configuration(s), {kind} ({plan.method})"
    )
    print(
        f"h* (min over configurations): {min(plan.h_star_before_s):.4g} s -> "
        f"{min(plan.h_star_after_s):.4g} s"
    )
    rows = _armature_rows(
        plan.dof_names,
        plan.armature,
        robot.model,
        plan.inertia_percent,
        plan.servo_frequency_before_rad_s,
        plan.servo_frequency_after_rad_s,
    )
    header = ["coordinate", "armature", "unit", "% of M_ii", "servo_rad_s", "after_rad_s"]
    print(table(header, rows))
    gap = "" if not plan.per_joint else f" (least total >= {plan.lower_bound:.6g})"
    print(f"total {plan.total:.6g}{gap}")
    change = np.array(plan.qdd_change)
    print(f"q̈ under gravity changes by {change.max():.1%} (max over the configurations)")
    return 0
