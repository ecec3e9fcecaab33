"""Write the URDF of a chain of homogeneous rods (stdout, or a file with -o)."""

from __future__ import annotations

import argparse
import sys

from gimwatch.cli._format import float_list, positive_int
from gimwatch.model.chains import (
    AXIS_LAYOUTS,
    JOINT_TYPES,
    PAPER_CHAIN,
    chain_spec,
    generate_chain_urdf,
)
from gimwatch.output.atomic import write_text_atomic

NAME = "chain"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("n", type=positive_int, help="number of links")
    parser.add_argument(
        "--mass",
        type=float_list,
        default=[PAPER_CHAIN["mass_kg"]],
        help="mass of each rod in kg, or a comma-separated list (default 2.2)",
    )
    parser.add_argument(
        "--length",
        type=float_list,
        default=[PAPER_CHAIN["length_m"]],
        help="length of each rod in m, or a list (default 1.0)",
    )
    parser.add_argument(
        "--radius",
        type=float_list,
        default=[PAPER_CHAIN["radius_m"]],
        help="rod radius in m, 0 = slender rod, or a list (default 0)",
    )
    parser.add_argument(
        "--axes",
        default="planar",
        help=f"{' or '.join(AXIS_LAYOUTS)} (alternating z, y), or a list of x/y/z",
    )
    parser.add_argument(
        "--joint-types",
        default="revolute",
        help=f"{' or '.join(JOINT_TYPES)}, or a comma-separated list",
    )
    parser.add_argument("-o", "--output", help="write to this file instead of stdout")


def run(args: argparse.Namespace) -> int:
    """Generate the chain and write it."""
    axes = args.axes if args.axes in AXIS_LAYOUTS else args.axes.split(",")
    kinds = args.joint_types.split(",") if "," in args.joint_types else args.joint_types
    spec = chain_spec(
        args.n,
        mass_kg=args.mass,
        length_m=args.length,
        radius_m=args.radius,
        axes=axes,
        joint_types=kinds,
    )
    text = generate_chain_urdf(spec)
    if args.output:
        write_text_atomic(args.output, text)
        print(f"wrote {args.output} ({spec.n} links)", file=sys.stderr)
    else:
        sys.stdout.write(text)
    return 0
