"""``gimwatch bench``: measure what accuracy costs in time (conditioning, estimators, q̈)."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from gimwatch.bench import SECTIONS, run_bench
from gimwatch.cli._format import non_negative_int
from gimwatch.errors import InputError, OutputError

NAME = "bench"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "which",
        nargs="*",
        default=["all"],
        metavar="SECTION",
        help=f"sections to run: {', '.join(SECTIONS)} or all (default: all)",
    )
    parser.add_argument("-o", "--output", default="benchmarks", help="output folder")
    parser.add_argument("--quick", action="store_true", help="tiny sizes: a smoke run")
    parser.add_argument(
        "--replot",
        action="store_true",
        help="measure nothing: redraw the figures of --output from its JSON tables",
    )
    parser.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of every random draw"
    )
    parser.add_argument(
        "--page",
        "--readme",
        dest="page",
        default=None,
        metavar="FILE",
        help="regenerate the block between the bench markers of this Markdown page "
        "(<!-- bench:DIR:start/end --> for output folder DIR when it has them, else "
        "<!-- bench:start/end -->; make bench: docs/findings/accuracy-costs.md)",
    )


def _check_page(page: Path, output: str) -> None:
    """The page --page regenerates must exist and hold the bench markers."""
    from gimwatch.bench.report import page_markers

    try:
        text = page.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise OutputError(str(page), f"cannot be read ({exc.__class__.__name__})") from exc
    start, end = page_markers(text, output)
    if start not in text or end not in text:
        raise InputError(f"{page}", f"a file with {start} and {end} markers", "no markers")


def _progress(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def run(args: argparse.Namespace) -> int:
    """Run the sections and print the report (or, with --replot, only redraw the figures)."""
    if args.replot:
        from gimwatch.bench.plots import replot

        for path in replot(args.output):
            print(path)
        return 0
    which = ["all"] if "all" in args.which else args.which
    if args.page is not None:
        _check_page(Path(args.page), args.output)  # before the sections run, not after
    report = run_bench(
        which,
        args.output,
        quick=args.quick,
        progress=_progress,
        readme=args.page,
        seed=args.seed,
    )
    print(report.read_text())
    print(f"wrote {report}", file=sys.stderr)
    return 0
