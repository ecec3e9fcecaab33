"""docs/findings/stability.md is its committed CSV, and the CSV is what the code computes.

The table between the page's markers is regenerated from ``benchmarks/stability/stable_steps.csv``
(`page_table`), every sentence's figure is recomputed from the CSV or its summary, and two
rows of the CSV are recomputed with `gimwatch.stability` now (a stale table fails).
"""

from __future__ import annotations

import importlib.util
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "docs" / "findings" / "stability.md"
_spec = importlib.util.spec_from_file_location(
    "stable_steps", ROOT / "benchmarks" / "stability" / "stable_steps.py"
)
steps = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(steps)
ROWS = steps.read_rows()
SUMMARY = json.loads((ROOT / "benchmarks" / "stability" / "summary.json").read_text())


def test_the_table_is_the_committed_csv():
    text = PAGE.read_text(encoding="utf-8")
    block = text.split("<!-- stability:start -->\n", 1)[1].split("<!-- stability:end -->", 1)[0]
    assert block == steps.page_table(ROWS)


def test_the_summary_is_the_csvs():
    assert steps.summary(ROWS) == SUMMARY


def test_the_sentences_quote_the_csv():
    text = " ".join(PAGE.read_text(encoding="utf-8").split())
    euler = [r for r in ROWS if r["integrator"] == "Euler"]
    short = [r for r in euler if float(r["h_star_s"]) < 0.002]  # MuJoCo's default step
    assert f"`Euler` on {len(short)} of the {len(euler)} arms" in text
    assert all(r["limited_by"] == "explicit damping" for r in short)
    damped = [r for r in euler if r["limited_by"] == "explicit damping"]
    assert all(float(r["two_over_omega_s"]) > float(r["h_star_s"]) for r in damped)
    by = {(r["robot"], r["integrator"]): float(r["h_star_s"]) for r in ROWS}
    for r in euler:
        assert 1 / 3 <= by[(r["robot"], "RK4")] / by[(r["robot"], "Euler")] <= 3, r["robot"]
        assert by[(r["robot"], "implicitfast")] >= 0.01, r["robot"]
    for integrator, values in SUMMARY.items():
        if isinstance(values, dict):
            for value in values.values():
                figure = rf"(?<![\d.]){re.escape(str(value))}(?![\d])"
                assert re.search(figure, text), (integrator, value)


@pytest.mark.parametrize(("robot", "integrator"), [("ur5e", "Euler"), ("ur5", "RK4")])
def test_rows_are_what_the_code_computes_now(robot, integrator):
    rows = {
        r["robot"]: {k: str(v) for k, v in r.items()}
        for r in steps.measure_robot(robot)
        if r["integrator"] == integrator
    }
    committed = next(r for r in ROWS if r["robot"] == robot and r["integrator"] == integrator)
    assert rows[robot] == committed
