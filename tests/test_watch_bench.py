"""The ``watch_mujoco`` bench section measures what it claims (never how fast)."""

import csv
import io

from gimwatch.bench import run_bench
from gimwatch.bench.watch_mujoco import COLUMNS, ROBOTS, WATCHES


def test_quick_watch_mujoco_section_has_one_row_per_robot_and_watch(tmp_path):
    report = run_bench(["watch_mujoco"], tmp_path, quick=True)
    rows = list(csv.DictReader(io.StringIO((tmp_path / "watch_mujoco.csv").read_text())))
    assert tuple(rows[0]) == COLUMNS
    expected = {
        (spec.replace(":", "_"), *label.split("/")) for spec in ROBOTS[:2] for label in WATCHES
    }
    assert {(r["robot"], r["watch"], r["source"]) for r in rows} == expected
    for row in rows:
        assert float(row["step_us"]) > 0 and float(row["sample_us"]) > 0, row
        assert float(row["sample_vs_step"]) > 0, row
    text = report.read_text()
    assert "Cost of the watch in a MuJoCo loop" in text and "sample / mj_step" in text
