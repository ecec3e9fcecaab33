"""Small text helpers shared by the subcommands."""

from __future__ import annotations

import argparse
import os
from argparse import ArgumentTypeError
from collections.abc import Sequence

from gimwatch.errors import InputError


def table(headers: Sequence[str], rows: Sequence[Sequence[object]]) -> str:
    """An aligned plain-text table; floats in 4 significant digits.

    Numbers are right-aligned, text left-aligned (a column of names reads down its left edge).
    """

    def cell(value: object) -> str:
        if value is None:
            return "-"
        return f"{value:.4g}" if isinstance(value, float) else str(value)

    cells = [[cell(v) for v in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in cells)) for i, h in enumerate(headers)]
    lines = ["  ".join(h.ljust(w) for h, w in zip(headers, widths, strict=True))]
    lines.append("  ".join("-" * w for w in widths))
    numeric = [
        all(isinstance(row[i], int | float) or row[i] is None for row in rows)
        for i in range(len(headers))
    ]
    lines += [
        "  ".join(
            c.rjust(w) if num else c.ljust(w)
            for c, w, num in zip(row, widths, numeric, strict=True)
        ).rstrip()
        for row in cells
    ]
    return "\n".join(line.rstrip() for line in lines)


def float_list(text: str) -> list[float]:
    """Parse ``"1.0"`` or ``"1,2,3"`` into floats (argparse ``type=``)."""
    try:
        return [float(x) for x in text.split(",")]
    except ValueError:
        raise ArgumentTypeError(
            f"must be a number or a comma-separated list of numbers, got {text!r}"
        ) from None


def positive_int(text: str) -> int:
    """Parse a positive integer (argparse ``type=``)."""
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or value < 1:
        raise ArgumentTypeError(f"must be a positive integer, got {text!r}")
    return value


def non_negative_int(text: str) -> int:
    """Parse an integer >= 0 (argparse ``type=``)."""
    try:
        value = int(text)
    except ValueError:
        value = None
    if value is None or value < 0:
        raise ArgumentTypeError(f"must be an integer >= 0, got {text!r}")
    return value


def add_base_arguments(parser: argparse.ArgumentParser) -> None:
    """``--floating`` / ``--fixed`` into ``floating`` (None: the robot's default base)."""
    base = parser.add_mutually_exclusive_group()
    base.add_argument(
        "--floating",
        dest="floating",
        action="store_const",
        const=True,
        default=None,
        help="a free-flyer base (default: example-robot-data's base for its robots, a "
        "free-flyer for legged robots and humanoids; fixed for chains and files)",
    )
    base.add_argument(
        "--fixed", dest="floating", action="store_const", const=False, help="a fixed base"
    )


def add_mjcf_arguments(parser) -> None:
    """``--body`` and ``--no-armature``: how an MJCF file is read (ignored for URDF)."""
    parser.add_argument(
        "--body",
        default="",
        metavar="NAME",
        help="MJCF: read only the subtree of this body (default: the whole model, free "
        "objects included, as MuJoCo's nv)",
    )
    parser.add_argument(
        "--no-armature",
        action="store_true",
        help="MJCF: leave MuJoCo's joint armature out of M (MuJoCo's M includes it)",
    )


#: Local worker processes allowed above the cores (``$GIMWATCH_MAX_WORKERS`` overrides):
#: each holds a Pinocchio model and its Data, and more than the cores only adds memory.
MAX_WORKERS_VARIABLE = "GIMWATCH_MAX_WORKERS"


def max_workers() -> int:
    """The most local worker processes: the cores this process may run on, or the variable."""
    text = os.environ.get(MAX_WORKERS_VARIABLE, "").strip()
    if text:
        if not text.isdigit() or int(text) < 1:
            raise InputError(f"${MAX_WORKERS_VARIABLE}", "a positive integer", text)
        return int(text)
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def check_workers(workers: int | None) -> None:
    """Refuse more local worker processes than `max_workers` (``--workers``)."""
    limit = max_workers()
    if workers is not None and workers > limit:
        raise InputError(
            "--workers",
            f"at most {limit}, the cores of this machine (set ${MAX_WORKERS_VARIABLE} to "
            "allow more)",
            workers,
        )
