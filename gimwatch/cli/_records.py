"""Data out of the command line: one JSON shape per command, CSV with fixed columns.

Every command with ``--json`` prints one object whose list fields hold the rows, whatever
their number (``{"robot": ..., "configurations": [...]}``); ``--csv`` prints the same rows,
one line each, under a fixed header. Vectors in a CSV cell are ``;``-separated.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping, Sequence

from gimwatch.output.atomic import to_json

__all__ = ["add_output_arguments", "csv_text", "json_text"]


def add_output_arguments(parser, *, what: str) -> None:
    """Add the mutually exclusive ``--json`` / ``--csv`` flags to a subcommand."""
    group = parser.add_mutually_exclusive_group()
    group.add_argument(
        "--json", action="store_true", help=f"print one JSON object with a list of {what}"
    )
    group.add_argument("--csv", action="store_true", help=f"print {what} as CSV, one per line")


def json_text(record: Mapping) -> str:
    """The JSON text of one record (NaN and infinities as ``null``)."""
    return to_json(dict(record))


def _cell(value: object) -> object:
    if value is None:
        return ""
    if isinstance(value, list | tuple):
        return ";".join(repr(float(v)) if isinstance(v, float) else str(v) for v in value)
    if isinstance(value, float):
        return repr(value)
    return value


def csv_text(rows: Iterable[Mapping], columns: Sequence[str]) -> str:
    """CSV with the header ``columns`` and one line per row (missing keys are empty)."""
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow([_cell(row.get(column)) for column in columns])
    return buffer.getvalue().rstrip("\n")
