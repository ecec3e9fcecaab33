"""The main job: the paper's swinging 4-, 10- and 20-link chains, watched.

Writes figures in the spirit of the paper's Figs. 2-5 and a report.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gimwatch.cli._progress import ProgressBar
from gimwatch.demo import run_demo

NAME = "demo"
HELP = "the main job: the paper's swinging 4-, 10- and 20-link chains, watched"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("-o", "--output", default="demo-output", help="output folder")


def run(args: argparse.Namespace) -> int:
    """Run the demo, print the report and say where it is."""
    bars: list[ProgressBar] = []

    def progress(n: int) -> ProgressBar:
        if bars:
            bars[-1].close()
        bars.append(ProgressBar(f"chain_{n}"))
        return bars[-1]

    try:
        report = run_demo(Path(args.output), progress=progress)
    finally:
        if bars:
            bars[-1].close()
    print(report.read_text())
    print(f"wrote {report}", file=sys.stderr)
    return 0
