"""The records every bench section returns: fixed-column tables, its result, its context.

In a module of their own so that the report writer (`gimwatch.bench.report`), which the
package's run imports, can read them without importing the package back.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["BenchContext", "SectionResult", "Table"]


@dataclass(frozen=True)
class Table:
    """A result table with fixed columns (CSV header and JSON keys, in this order)."""

    name: str
    columns: tuple[str, ...]
    rows: list[dict] = field(default_factory=list)

    def add(self, **row: object) -> None:
        """Append a row; its keys must be exactly the table's columns."""
        if set(row) != set(self.columns):
            missing, extra = set(self.columns) - set(row), set(row) - set(self.columns)
            raise KeyError(f"table {self.name}: missing {sorted(missing)}, extra {sorted(extra)}")
        self.rows.append({c: row[c] for c in self.columns})


@dataclass
class SectionResult:
    """What one section measured: tables, figure files, and its Markdown text.

    Attributes:
        name: The section's registry name.
        title: Its heading.
        tables: The fixed-column tables (written as ``<name>.csv`` and ``<name>.json``).
        figures: PNG files written into the output folder.
        markdown: The section's report text (headline tables and conclusions).
        headline: A shorter text for the docs page "What accuracy costs".
        summary: Key figures for ``summary.json`` (ratios, acceptance checks).
        measured_code: The fingerprint of the code measured
            (`gimwatch.bench.freshness.fingerprint`), written into each table's JSON;
            filled by the run when the section leaves it empty.
    """

    name: str
    title: str
    tables: list[Table] = field(default_factory=list)
    figures: list[Path] = field(default_factory=list)
    markdown: str = ""
    headline: str = ""
    summary: dict = field(default_factory=dict)
    measured_code: dict = field(default_factory=dict)


@dataclass(frozen=True)
class BenchContext:
    """What a section gets: where to write, how big to go, where to say how far it is.

    Attributes:
        output: The output folder (exists).
        quick: Tiny sizes: a smoke run for CI, numbers meaningless.
        progress: Called with one line of progress (the CLI prints it on stderr).
        seed: Seed of every random draw in the run.
    """

    output: Path
    quick: bool = False
    progress: Callable[[str], None] = lambda line: None
    seed: int = 0
