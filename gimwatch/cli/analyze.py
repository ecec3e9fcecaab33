"""Conditioning of a robot's GIM at the neutral, given or random configurations."""

from __future__ import annotations

import argparse
import sys

from gimwatch.cli._batch import expand_specs
from gimwatch.cli._format import (
    add_base_arguments,
    add_mjcf_arguments,
    non_negative_int,
    positive_int,
    table,
)
from gimwatch.cli._progress import ItemProgress
from gimwatch.cli._records import add_output_arguments, csv_text, json_text
from gimwatch.errors import GimwatchError, InputError
from gimwatch.metrics.analyze import Analysis, analyze, resolve_robot
from gimwatch.model.robot_spec import RobotSpec
from gimwatch.model.robots import DATA_NV_LIMIT
from gimwatch.model.sampling import placeholder_note

NAME = "analyze"
#: More configurations than this would print a table nobody reads; use ``survey``.
MAX_RANDOM = 100_000
#: ``--csv`` columns, one row per configuration (vectors ``;``-separated).
CSV_COLUMNS = (
    "config",
    "robot",
    "nv",
    "method",
    "kappa",
    "diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "kappa_equilibrated",
    "lambda_min",
    "lambda_max",
    "max_diagonal_dof",
    "min_diagonal_dof",
    "q",
    "eigenvalues",
    "diagonal",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "robots",
        nargs="+",
        metavar="ROBOT",
        help="chain:N, a URDF/MJCF path or a folder of them, or an example-robot-data name; "
        "given several, a refused one is a row 'refused: <reason>' and the exit status 2",
    )
    parser.add_argument(
        "--q",
        type=float,
        nargs="+",
        metavar="Q",
        help="configuration: nq numbers, a continuous joint by its angle (rad); for MJCF, "
        "MuJoCo's qpos; default: neutral",
    )
    parser.add_argument(
        "--random",
        type=positive_int,
        metavar="K",
        help="analyse K random configurations within the joint limits",
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the random draws")
    add_base_arguments(parser)
    add_mjcf_arguments(parser)
    add_output_arguments(parser, what="configurations")
    parser.add_argument(
        "--backend",
        choices=("auto", "crba", "denoc"),
        default="auto",
        help="crba: dense M from Pinocchio; denoc: the O(n) path (no Data, no dense M; URDF and "
        "MJCF trees of hinges, slides, ball and free joints, several trees); auto: denoc above "
        f"nv = {DATA_NV_LIMIT}, where Pinocchio's Data needs GBs",
    )
    # --explain (issue 25): the modes of λmin and λmax at each configuration, dense path only
    parser.add_argument(
        "--explain",
        action="store_true",
        help="also explain kappa: the joints and bodies of the lambda_min and lambda_max modes",
    )
    parser.add_argument(
        "--metrics",
        help="comma-separated subset of kappa,diagonal_ratio,pivot_ratio_backward,"
        "kappa_equilibrated to compute on the O(n) path (default: all four)",
    )


def run(args: argparse.Namespace) -> int:
    """Analyse and print: one robot as before, several as a batch with refusals kept."""
    if args.q is not None and args.random is not None:
        raise InputError("--q and --random", "used one at a time", "both")
    if args.random is not None and args.random > MAX_RANDOM:
        raise InputError("--random", f"at most {MAX_RANDOM}", args.random)
    specs = expand_specs(args.robots)
    if len(specs) == 1:
        analysis = _analysis(specs[0], args)
        _notes(analysis)
        if args.explain:
            return _print_explained(analysis, args)
        return _print_one(analysis, args)
    if args.explain:
        raise InputError("--explain", "used with one robot", f"{len(specs)} robots")
    blocks: list[tuple[str, object, str]] = []
    progress = ItemProgress("analyze", len(specs))
    for spec in specs:
        progress.start(spec)
        try:
            analysis = _analysis(spec, args)
        except GimwatchError as exc:
            blocks.append((spec, None, str(exc)))
            continue
        _notes(analysis)
        blocks.append((spec, analysis, ""))
    progress.close()
    _print_batch(blocks, args)
    return 2 if any(reason for _, _, reason in blocks) else 0


def _analysis(spec: str, args: argparse.Namespace) -> Analysis:
    """The robot parsed once, loaded at most once (to choose the path), then analysed."""
    parsed = RobotSpec.parse(spec, args.floating, body=args.body, armature=not args.no_armature)
    path, robot = resolve_robot(parsed, args.backend)
    linear = path == "denoc"
    if args.metrics is not None and not linear:
        raise InputError("--metrics", "used with the O(n) path (--backend denoc)", args.metrics)
    if args.explain and (linear or args.csv):
        raise InputError("--explain", "used on the dense path, without --csv", True)
    return analyze(
        robot,
        args.q,
        random=args.random,
        seed=args.seed,
        backend=args.backend,
        metrics=None if args.metrics is None else args.metrics.split(","),
        key="--q",
    )


def _notes(analysis) -> None:
    first = analysis.results[0]
    if analysis.placeholder_limits:
        print(f"gimwatch: note: {placeholder_note(analysis.placeholder_limits)}", file=sys.stderr)
    if analysis.mixed_units:
        lengths, angles = analysis.units
        print(
            f"gimwatch: note: {first.robot} mixes units ({lengths} length and {angles} angle "
            "coordinates): kappa and diagonal_ratio depend on the unit of length, "
            "kappa_equilibrated does not",
            file=sys.stderr,
        )
    if analysis.path == "denoc" and analysis.chosen:
        print(
            f"gimwatch: {first.robot} has nv = {first.nv} > {DATA_NV_LIMIT}: using the O(n) "
            "DeNOC path (Pinocchio's Data would need GBs)",
            file=sys.stderr,
        )


def _header(analysis) -> dict:
    first = analysis.results[0]
    base = "floating" if analysis.floating else "fixed"
    header = {"robot": first.robot, "nv": first.nv, "base": base, "method": first.method}
    if analysis.placeholder_limits:  # random draws replaced these joints' limits
        header["placeholder_limits"] = list(analysis.placeholder_limits)
    return header


def _records(analysis) -> list[dict]:
    return [{"config": i, **r.to_dict()} for i, r in enumerate(analysis.results)]


def _print_one(analysis, args: argparse.Namespace) -> int:
    records = _records(analysis)
    if args.json:
        print(json_text({**_header(analysis), "configurations": records}))
        return 0
    if args.csv:
        print(csv_text(records, CSV_COLUMNS))
        return 0
    _print_table(analysis)
    return 0


def _print_table(analysis) -> None:
    first, results = analysis.results[0], analysis.results
    base = "floating" if analysis.floating else "fixed"
    print(f"{first.robot}: nv = {first.nv}, {base} base, method {first.method}")
    # the registry's names, as in --json and --csv
    headers = [
        "config",
        "kappa",
        "diagonal_ratio",
        "pivot_ratio_forward",
        "pivot_ratio_backward",
        "kappa_equilibrated",
        "lambda_min",
        "lambda_max",
        "max_diagonal_dof",
        "min_diagonal_dof",
    ]
    rows = [
        [
            i,
            r.kappa,
            r.diagonal_ratio,
            r.pivot_ratio_forward,
            r.pivot_ratio_backward,
            r.kappa_equilibrated,
            r.lambda_min,
            r.lambda_max,
            r.max_diagonal_dof,
            r.min_diagonal_dof,
        ]
        for i, r in enumerate(results)
    ]
    print(table(headers, rows))


#: ``--csv`` columns of a batch: a refused robot is a row with its reason in ``refused``.
BATCH_CSV_COLUMNS = (*CSV_COLUMNS, "refused")


def _print_batch(blocks, args: argparse.Namespace) -> None:
    if args.json:
        robots = [
            {**_header(a), "configurations": _records(a)}
            if a is not None
            else {"robot": spec, "status": "refused", "reason": reason}
            for spec, a, reason in blocks
        ]
        print(json_text({"robots": robots}))
        return
    if args.csv:
        rows = []
        for spec, a, reason in blocks:
            if a is None:
                rows.append({"robot": spec, "refused": reason})
            else:
                rows.extend({**r, "refused": ""} for r in _records(a))
        print(csv_text(rows, BATCH_CSV_COLUMNS))
        return
    for spec, a, reason in blocks:
        if a is None:
            print(f"{spec}: refused: {reason}")
        else:
            _print_table(a)
        print()
    refused = sum(1 for _, a, _ in blocks if a is None)
    print(
        f"{len(blocks) - refused}/{len(blocks)} analysed" + (f", {refused} refused" * bool(refused))
    )


def _print_explained(analysis: Analysis, args: argparse.Namespace) -> int:
    """``--explain``: the analysis, and the modes of λmin and λmax at each configuration."""
    from gimwatch.cli.explain import mode_lines
    from gimwatch.explain.modes import gim_modes

    robot = analysis.robot  # the robot analysed: the dense path always loads it
    assert robot is not None
    modes = [gim_modes(robot, r.q) for r in analysis.results]
    if args.json:
        records = [
            {**r, "modes": m.to_dict()} for r, m in zip(_records(analysis), modes, strict=True)
        ]
        print(json_text({**_header(analysis), "configurations": records}))
        return 0
    _print_table(analysis)
    for i, mode in enumerate(modes):
        for line in mode_lines(mode):
            print(f"config {i}: {line}")
    return 0
