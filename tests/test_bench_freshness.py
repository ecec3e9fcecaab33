"""Every committed benchmark table is no older than the code it measured.

``gimwatch bench`` writes, into each table's JSON, the digests of the gimwatch modules the
measuring process had imported (`gimwatch.bench.freshness`). A change to any of them since
makes the table stale: regenerate it with the command in its folder's report (``make bench``
regenerates them all in one run).
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from gimwatch.bench.freshness import FINGERPRINT_KEY, stale_modules

ROOT = Path(__file__).resolve().parents[1]
TABLES = sorted(
    path
    for path in (ROOT / "benchmarks").rglob("*.json")
    if '"columns"' in path.read_text(encoding="utf-8")[:200]
)


def test_the_bench_tables_are_found():
    names = {path.relative_to(ROOT / "benchmarks").as_posix() for path in TABLES}
    assert {"conditioning.json", "cost/lean.json", "watch_overhead/watch_overhead.json"} <= names


@pytest.mark.parametrize("path", TABLES, ids=[p.relative_to(ROOT).as_posix() for p in TABLES])
def test_a_bench_table_is_not_older_than_the_code_it_measured(path):
    record = json.loads(path.read_text(encoding="utf-8"))
    assert FINGERPRINT_KEY in record, f"{path}: no fingerprint; regenerate it (make bench)"
    assert record[FINGERPRINT_KEY]["modules"], f"{path}: an empty fingerprint"
    stale = stale_modules(record[FINGERPRINT_KEY], ROOT)
    assert not stale, f"{path} predates changes to {stale}: regenerate it (make bench)"
