"""Every column gimwatch writes is named in docs/units.md, with its unit."""

from __future__ import annotations

import re
from pathlib import Path

import gimwatch as gw
from gimwatch.cli.analyze import CSV_COLUMNS as ANALYZE_COLUMNS
from gimwatch.cli.crosscheck import CSV_COLUMNS as CROSSCHECK_COLUMNS
from gimwatch.survey.report import CSV_COLUMNS as SURVEY_COLUMNS
from gimwatch.watch.watch import METRICS

ROOT = Path(__file__).resolve().parents[1]


def _documented() -> list[re.Pattern]:
    """One pattern per name of the table's first column (``<joint>`` matches any name)."""
    patterns = []
    for line in (ROOT / "docs" / "units.md").read_text(encoding="utf-8").splitlines():
        if not line.startswith("| `"):
            continue
        first = line.split(" | ")[0]
        for name in re.findall(r"`([^`]+)`", first):
            patterns.append(re.compile(re.sub(r"<\w+>", ".+", re.escape(name)) + "$"))
    return patterns


def _missing(columns) -> list[str]:
    patterns = _documented()
    return [c for c in columns if not any(p.match(c) for p in patterns)]


def test_every_table_column_is_documented():
    columns = {*ANALYZE_COLUMNS, *CROSSCHECK_COLUMNS, *SURVEY_COLUMNS, *METRICS}
    assert not _missing(sorted(columns))


def test_every_trajectory_and_watch_column_is_documented():
    scene = gw.parse_scene(
        {
            "robot": "chain:2",
            "duration": 0.1,
            "sample": 0.05,
            "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
            "watch": {"metrics": ["kappa", "diagonal_ratio", "eigenvalues", "diagonal"]},
        }
    )
    trajectory = gw.run_scene(scene)
    frame = trajectory.to_dataframe()
    assert not _missing(list(frame.columns))
    # the arrays name the same series watch_<name>
    assert {f"watch_{c}" for c in ("t", "kappa", "diagonal_ratio")} <= set(trajectory.watch)


def test_the_table_is_read():
    assert len(_documented()) > 30 and not _missing(["q:elbow", "eigenvalues:3", "t"])
    assert _missing(["kappa_of_something_else"]) == ["kappa_of_something_else"]
