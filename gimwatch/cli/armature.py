"""The least joint armature that brings κ under a target at given or random configurations."""

from __future__ import annotations

import argparse

import numpy as np

from gimwatch.cli._format import non_negative_int, positive_int, table
from gimwatch.cli._records import json_text
from gimwatch.errors import InputError
from gimwatch.explain.armature import minimal_armature
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot, random_configurations

NAME = "armature"
HELP = "the least joint armature that brings kappa under a target, and what it costs"
#: More configurations than this make each cutting-plane round slow; sample fewer.
MAX_SAMPLES = 100_000


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("robot", help="chain:N, a URDF or MJCF path, or an example-robot-data name")
    parser.add_argument(
        "--target", type=float, required=True, metavar="KAPPA", help="the largest kappa allowed"
    )
    parser.add_argument(
        "--samples", type=positive_int, default=100, metavar="K", help="random configurations"
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
        kind = joint.shortname()
        if "Prismatic" in kind or (kind.startswith("JointModelP") and "Planar" not in kind):
            units += ["kg"] * joint.nv
        elif "FreeFlyer" in kind:
            units += ["kg"] * 3 + ["kg*m^2"] * 3
        elif "Planar" in kind:
            units += ["kg"] * 2 + ["kg*m^2"]
        else:
            units += ["kg*m^2"] * joint.nv
    return units


def run(args: argparse.Namespace) -> int:
    """Compute and print."""
    if args.samples > MAX_SAMPLES:
        raise InputError("--samples", f"at most {MAX_SAMPLES}", args.samples)
    if not np.isfinite(args.target) or args.target <= 1.0:
        raise InputError("--target", "a number > 1 (κ ≥ 1 always)", args.target)
    robot = load_robot(args.robot, max_nv=DATA_NV_LIMIT)
    if args.q is not None:
        qs = user_configuration(robot, args.q, key="--q")[None, :]
    else:
        qs = random_configurations(robot, args.samples, seed=args.seed)
    plan = minimal_armature(robot, qs, args.target, per_joint=args.per_joint)
    if args.json:
        print(json_text(plan.to_dict()))
        return 0
    kind = "per joint (least total)" if plan.per_joint else "uniform"
    print(f"{robot.name}: target kappa {plan.target:g} over {len(qs)} configuration(s), {kind}")
    print(f"kappa max: {max(plan.kappa_before):.6g} -> {max(plan.kappa_after):.6g}")
    rows = [
        [name, _shown(value, max(plan.armature)), unit]
        for name, value, unit in zip(
            plan.dof_names, plan.armature, _armature_units(robot.model), strict=True
        )
    ]
    print(table(["coordinate", "armature", "unit"], rows))
    gap = "" if not plan.per_joint else f" (least total >= {plan.lower_bound:.6g})"
    print(f"total {plan.total:.6g}{gap}")
    change = np.array(plan.qdd_change)
    print(
        f"q̈ under gravity changes by {np.median(change):.1%} (median), "
        f"{change.max():.1%} (max) over the configurations"
    )
    return 0
