"""The main job: analyse the paper's 4-, 10- and 20-link chains and write a report."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gimwatch.demo import run_demo

NAME = "demo"
HELP = "the main job: the paper's 4-, 10- and 20-link chains"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("-o", "--output", default="demo-output", help="output folder")


def run(args: argparse.Namespace) -> int:
    """Run the demo and say where its report is."""
    report = run_demo(Path(args.output))
    print(report.read_text())
    print(f"wrote {report}", file=sys.stderr)
    return 0
