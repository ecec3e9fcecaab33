"""Cross-check DeNOC (numpy + yourdfpy) against Pinocchio: GIM, τ, q̈ and UDUᵀ pivots.

ROBOT is chain:N, a URDF or MJCF path, a folder of them, an example-robot-data name, or
``all`` (every example-robot-data robot; those that cannot be loaded are skipped with the
reason on stderr). Given several robots, a refused one is a row ``refused: <reason>`` and the
others are still compared. Exit status: 2 when a robot was refused, else 1 when any robot is
beyond the tolerance or was not compared (nothing to compare: M ≡ 0), else 0.
"""

from __future__ import annotations

import argparse
import sys

from gimwatch.cli._batch import expand_specs, load_each
from gimwatch.cli._format import (
    add_base_arguments,
    add_mjcf_arguments,
    non_negative_int,
    positive_int,
    table,
)
from gimwatch.cli._progress import ItemProgress
from gimwatch.cli._records import add_output_arguments, csv_text, json_text
from gimwatch.crosscheck import (
    DEFAULT_TOLERANCE,
    CrossCheckResult,
    check_tolerance,
    crosscheck_robot,
)
from gimwatch.errors import GimwatchError
from gimwatch.model.example_robots import example_robot_names
from gimwatch.model.robots import load_robot

NAME = "crosscheck"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "robots", nargs="+", metavar="ROBOT", help="robot specs or folders of them, or 'all'"
    )
    parser.add_argument("--samples", type=positive_int, default=10, help="random states")
    parser.add_argument(
        "--seed", type=non_negative_int, default=0, help="seed of the random states"
    )
    add_base_arguments(parser)
    add_mjcf_arguments(parser)
    parser.add_argument(
        "--tolerance",
        type=float,
        default=DEFAULT_TOLERANCE,
        help="largest relative error that passes",
    )
    parser.add_argument(
        "--peer",
        choices=("mujoco",),
        default=None,
        help="also compare MuJoCo's mj_fullM with Pinocchio's crba (MJCF robots: always)",
    )
    add_output_arguments(parser, what="robots")


#: ``--csv`` columns, one row per robot (the fields of
#: [`CrossCheckResult`][gimwatch.crosscheck.CrossCheckResult]).
CSV_COLUMNS = tuple(CrossCheckResult.__dataclass_fields__)


def _refusal_record(spec: str, reason: str) -> dict:
    """A refused robot as a row: its spec, status ``refused`` and the reason in ``note``."""
    record = dict.fromkeys(CSV_COLUMNS)
    record.update(robot=spec, status="refused", note=reason, passed=False)
    return record


def _print(results: list, args: argparse.Namespace) -> None:
    """``results`` holds CrossCheckResult records and refusal rows (dicts), in order."""
    records = [r if isinstance(r, dict) else r.to_dict() for r in results]
    if args.json:
        print(json_text({"tolerance": args.tolerance, "robots": records}))
        return
    if args.csv:
        print(csv_text(records, CSV_COLUMNS))
        return
    checked = [r for r in results if not isinstance(r, dict)]
    headers = ["robot", "base", "nv", "GIM", "diag", "tau", "qdd", "qdd bwd", "pivots"]
    fields = [
        "gim_rel_err",
        "gim_diagonal_rel_err",
        "tau_rel_err",
        "qdd_rel_err",
        "qdd_backward_err",
        "pivots_rel_err",
    ]
    if any(r.mujoco_gim_rel_err is not None for r in checked):
        headers.append("M mujoco")
        fields.append("mujoco_gim_rel_err")
    headers.append("kappa")
    fields.append("kappa_max")
    rows = []
    for r in results:
        if isinstance(r, dict):
            rows.append([r["robot"], "refused", *[""] * (len(headers) - 2)])
            continue
        label = {"passed": "", "failed": "  FAIL", "not compared": "  NOT COMPARED"}[r.status]
        rows.append(
            [
                r.robot + label,
                "floating" if r.floating else "fixed",
                r.nv,
                *("n/a" if getattr(r, f) is None else getattr(r, f) for f in fields),
            ]
        )
    print(table(headers, rows))
    print(
        f"columns {headers[3]} to {headers[-2]}: worst relative error |x - x_ref|/|x_ref| "
        "over the samples; kappa: the largest"
    )
    for r in results:
        if isinstance(r, dict):
            print(f"{r['robot']}: refused: {r['note']}")
        elif r.note:
            print(f"{r.robot}: {r.note}")
    counts = {s: sum(r.status == s for r in checked) for s in ("passed", "failed", "not compared")}
    refused = len(results) - len(checked)
    tolerance = checked[0].tolerance if checked else args.tolerance
    extra = "".join(
        f", {n} {what}"
        for n, what in ((counts["not compared"], "not compared"), (refused, "refused"))
        if n
    )
    print(f"{counts['passed']}/{len(results)} passed (tolerance {tolerance:g}){extra}")


def _status(results: list) -> int:
    if any(isinstance(r, dict) for r in results):
        return 2
    return 0 if all(r.status == "passed" for r in results) else 1


def _loaded(args: argparse.Namespace, specs: list[str], everything: bool):
    """(spec, robot or None, error or None) of each robot; one robot's bad input is an error."""
    mjcf = {"body": args.body, "armature": not args.no_armature}
    if len(specs) == 1 and not everything:  # one robot: bad input is one error line
        robot = load_robot(specs[0], floating=args.floating, **mjcf)
        return iter([(specs[0], robot, None)])
    return load_each(specs, floating=args.floating, **mjcf)


def _check_one(spec: str, robot, args: argparse.Namespace, alone: bool):
    """The robot's CrossCheckResult, or its refusal row when others are compared too."""
    try:
        return crosscheck_robot(
            robot, samples=args.samples, seed=args.seed, tolerance=args.tolerance, peer=args.peer
        )
    except GimwatchError as exc:
        if alone:
            raise
        return _refusal_record(spec, str(exc))


def _check_each(loaded, args, specs, everything, progress, results: list) -> None:
    """Append each robot's result (or refusal row) to ``results``; skip failed loads of all."""
    for spec, robot, error in loaded:
        if progress is not None:
            progress.start(spec)
        if robot is not None:
            results.append(_check_one(spec, robot, args, alone=len(specs) == 1))
        elif everything:
            reason = getattr(error, "problem", str(error))
            print(f"crosscheck: skipped {spec}: {reason}", file=sys.stderr)
        else:
            results.append(_refusal_record(spec, str(error)))


def _finish(progress: ItemProgress | None, results: list, args: argparse.Namespace) -> None:
    """Close the progress bar, then print the results, if any."""
    if progress is not None:
        progress.close()
    if results:
        _print(results, args)


def run(args: argparse.Namespace) -> int:
    """Cross-check each robot and print the worst errors."""
    check_tolerance(args.tolerance, "--tolerance")
    everything = "all" in args.robots
    specs = list(example_robot_names()) if everything else expand_specs(args.robots)
    loaded = _loaded(args, specs, everything)
    results: list = []
    progress = ItemProgress("crosscheck", len(specs)) if len(specs) > 1 else None
    try:
        _check_each(loaded, args, specs, everything, progress, results)
    except KeyboardInterrupt:  # an interrupted run still prints what it compared
        _finish(progress, results, args)
        raise
    _finish(progress, results, args)
    return _status(results)
