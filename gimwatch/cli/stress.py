"""Run the stress suite: hard cases, q̈ errors per method against mpmath, and C·κ·eps."""

from __future__ import annotations

import argparse
import sys

from gimwatch.cli._format import non_negative_int, table
from gimwatch.cli._records import csv_text, json_text
from gimwatch.stress.cases import CASES
from gimwatch.stress.suite import METHODS, run_stress, stress_markdown

NAME = "stress"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    parser.add_argument(
        "cases", nargs="*", metavar="CASE", help=f"cases (default: all): {', '.join(CASES)}"
    )
    parser.add_argument("--quick", action="store_true", help="only the quick cases")
    parser.add_argument(
        "--no-simulate", action="store_true", help="skip the 5 s simulation of each case"
    )
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of v and tau")
    output = parser.add_mutually_exclusive_group()
    output.add_argument(
        "--json", action="store_true", help="print one JSON object with a list of cases"
    )
    output.add_argument("--csv", action="store_true", help="print the cases as CSV, one per line")
    output.add_argument("--markdown", action="store_true", help="print a Markdown table")


def _progress(line: str) -> None:
    print(line, file=sys.stderr, flush=True)


def _flat(record: dict) -> dict:
    """The record with ``errors`` spread into ``error_<method>`` columns (for CSV)."""
    errors = record.pop("errors")
    return {**record, **{f"error_{method}": errors.get(method) for method in METHODS}}


def _cell(value: float | None) -> object:
    return "-" if value is None else value


def run(args: argparse.Namespace) -> int:
    """Run the cases, print the table; exit 1 when a case failed a check."""
    results = run_stress(
        args.cases or None,
        quick=args.quick,
        simulate=not args.no_simulate,
        seed=args.seed,
        progress=_progress,
    )
    records = [_flat(r.to_dict()) for r in results]
    if args.json:
        print(json_text({"cases": [r.to_dict() for r in results]}))
    elif args.csv:
        columns = [k for k in records[0] if k != "note"] + ["note"] if records else []
        print(csv_text(records, columns))
    elif args.markdown:
        print(stress_markdown(results))
    else:
        headers = ["case", "nv", "kappa", *METHODS, "C*kappa*eps", "DeNOC-M", "sim drift", "ok"]
        rows = [
            [
                r.case,
                r.nv,
                r.kappa,
                *(_cell(r.errors[m]) for m in METHODS),
                r.bound,
                _cell(r.gim_error),
                _cell(r.sim_energy_drift) if r.sim_status in ("completed", "") else r.sim_status,
                "yes" if r.passed else "NO",
            ]
            for r in results
        ]
        print(table(headers, rows))
        for r in results:
            if r.note:
                print(f"{r.case}: {r.note}", file=sys.stderr)
    return 0 if all(r.passed for r in results) else 1
