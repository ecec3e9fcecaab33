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


def test_quick_watch_overhead_section_times_each_loop_and_metric(tmp_path):
    from gimwatch.bench.watch_overhead import (
        CHAIN_SIZES,
        TRACKER_COLUMNS,
    )
    from gimwatch.bench.watch_overhead import (
        COLUMNS as OVERHEAD_COLUMNS,
    )
    from gimwatch.bench.watch_overhead import (
        ROBOTS as OVERHEAD_ROBOTS,
    )

    report = run_bench(["watch_overhead"], tmp_path, quick=True)
    rows = list(csv.DictReader(io.StringIO((tmp_path / "watch_overhead.csv").read_text())))
    assert tuple(rows[0]) == OVERHEAD_COLUMNS
    spec = OVERHEAD_ROBOTS[0][0]
    assert {(r["robot"], r["loop"], r["metric"]) for r in rows} == {
        (spec, loop, metric)
        for loop in ("mujoco", "pinocchio", "robot")
        for metric in ("kappa", "delta")
    }
    for row in rows:
        ratio = float(row["watch_us"]) / float(row["bare_us"])
        assert 0 < float(row["watch_vs_bare"]) < 10 * ratio, row  # a median of ratios, near
    tracker = list(csv.DictReader(io.StringIO((tmp_path / "watch_tracker.csv").read_text())))
    assert tuple(tracker[0]) == TRACKER_COLUMNS
    assert [int(r["n"]) for r in tracker] == list(CHAIN_SIZES[:2])
    assert "The watch sample against the bare computation" in report.read_text()
