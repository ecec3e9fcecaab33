"""List the metrics gimwatch computes, what each needs, and what it is.

Names are spelled as scenes and ``--metrics`` spell them.
``needs M``: the metric needs the dense GIM (an O(n²) CRBA and usually an O(n³)
factorisation); the others need only its O(n) diagonal or O(n) operators.
"""

from __future__ import annotations

import argparse

from gimwatch.cli._format import table
from gimwatch.cli._records import add_output_arguments, csv_text, json_text

NAME = "metrics"
#: ``--csv`` columns.
CSV_COLUMNS = ("name", "needs_M", "vector", "description")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Declare the subcommand's arguments."""
    add_output_arguments(parser, what="metrics")


def metric_rows() -> list[dict]:
    """One row per metric of the watch's registry."""
    from gimwatch.watch.watch import METRICS

    rows = []
    for name, metric in METRICS.items():
        doc = (metric.__doc__ or "").strip().split("\n\n")[0]
        rows.append(
            {
                "name": name,
                "needs_M": bool(getattr(metric, "full", True)),
                "vector": bool(getattr(metric, "vector", False)),
                "description": " ".join(doc.replace("``", "").split()),
            }
        )
    return rows


def run(args: argparse.Namespace) -> int:
    """Print the metric list."""
    rows = metric_rows()
    if args.json:
        print(json_text({"metrics": rows}))
    elif args.csv:
        print(csv_text(rows, CSV_COLUMNS))
    else:
        body = [
            [
                r["name"],
                "yes" if r["needs_M"] else "no",
                "vector" if r["vector"] else "scalar",
                r["description"],
            ]
            for r in rows
        ]
        print(table(["name", "needs M", "kind", "description"], body))
    return 0
