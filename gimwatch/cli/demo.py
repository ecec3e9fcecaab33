"""The main job: the paper's swinging 4-, 10- and 20-link chains, watched.

Writes figures in the spirit of the paper's Figs. 2-5 and a report.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gimwatch.cli._progress import ProgressBar
from gimwatch.cli._signals import LATCH
from gimwatch.demo import run_demo
from gimwatch.errors import InputError

NAME = "demo"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument("-o", "--output", default="demo-output", help="output folder")
    parser.add_argument("--duration", type=float, default=5.0, help="simulated seconds per chain")
    parser.add_argument(
        "--gif",
        action="store_true",
        help="also animate the 10-link chain as a GIF (about 80%% of the run time)",
    )
    # The GIF used to be drawn unless --no-gif; the flag is still accepted, and is the default.
    parser.add_argument("--no-gif", action="store_true", help=argparse.SUPPRESS)


def run(args: argparse.Namespace) -> int:
    """Run the demo, print the report and say where it is."""
    bars: list[ProgressBar] = []

    def progress(n: int) -> ProgressBar:
        if bars:
            bars[-1].close()
        bars.append(ProgressBar(f"chain_{n}"))
        return bars[-1]

    try:
        if not (args.duration > 0 and args.duration <= 60):
            raise InputError("--duration", "in (0, 60] s", args.duration)
        report = run_demo(
            Path(args.output),
            duration_s=args.duration,
            animate=10 if args.gif and not args.no_gif else None,
            progress=progress,
        )
    finally:
        if bars:
            bars[-1].close()
    print(report.read_text())
    print(f"wrote {report}", file=sys.stderr)
    if LATCH.signum is not None:
        print("gimwatch: interrupted; results so far were written", file=sys.stderr)
        return LATCH.exit_status
    return 0
