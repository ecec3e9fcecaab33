"""Every command ends quietly when the reader of its stdout has gone (``| head -1``).

Each command runs with a stdout whose read end is already closed, so its first write meets a
closed pipe: it must end with the exit status of its work (0 here), and nothing on stderr
but its own lines — no ``BrokenPipeError`` traceback, no "Exception ignored".
"""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

FAST = {
    "help": ["--help"],
    "chain": ["chain", "5"],
    "analyze-table": ["analyze", "ur5"],
    "analyze-json": ["analyze", "ur5", "--json"],
    "analyze-csv": ["analyze", "ur5", "--csv"],
    "analyze-random-csv": ["analyze", "ur5", "--random", "20", "--seed", "0", "--csv"],
    "robots": ["robots"],
    "metrics": ["metrics"],
    "explain": ["explain", "ur5"],
    "explain-json": ["explain", "ur5", "--json"],
    "armature": ["armature", "ur5", "--target", "50", "--samples", "3"],
    "map": ["map", "chain:3", "--joints", "joint_1", "joint_2", "--grid", "4", "-o", "{tmp}/map"],
    "crosscheck": ["crosscheck", "chain:3", "--samples", "2"],
    "crosscheck-json": ["crosscheck", "chain:3", "--samples", "2", "--json"],
}
SLOW = {
    "simulate": ["simulate", "chain_4", "-o", "{tmp}/sim"],
    "survey": ["survey", "ur5", "--samples", "3", "-o", "{tmp}/survey"],
    "stress": ["stress", "--quick", "--no-simulate", "straight-100"],
    "demo": ["demo", "-o", "{tmp}/demo"],
    "bench": ["bench", "startup", "--quick", "-o", "{tmp}/bench"],
}


def run_into_closed_pipe(argv: list[str], cwd: Path) -> subprocess.CompletedProcess:
    read_end, write_end = os.pipe()
    os.close(read_end)  # the reader is gone before the first byte
    try:
        return subprocess.run(
            [sys.executable, "-m", "gimwatch", *argv],
            stdout=write_end,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
            env={**os.environ, "PYTHONPATH": str(ROOT), "OMP_NUM_THREADS": "1"},
            timeout=900,
        )
    finally:
        os.close(write_end)


def _check(argv: list[str], tmp_path: Path) -> None:
    argv = [word.format(tmp=tmp_path) for word in argv]
    done = run_into_closed_pipe(argv, tmp_path)
    assert "Traceback" not in done.stderr and "BrokenPipe" not in done.stderr, done.stderr
    assert "Exception ignored" not in done.stderr, done.stderr
    assert done.returncode == 0, done.stderr


@pytest.mark.parametrize("argv", FAST.values(), ids=FAST.keys())
def test_command_ends_quietly_on_a_closed_pipe(argv, tmp_path):
    _check(argv, tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("argv", SLOW.values(), ids=SLOW.keys())
def test_long_command_ends_quietly_on_a_closed_pipe(argv, tmp_path):
    _check(argv, tmp_path)


def test_a_failed_check_keeps_its_status_on_a_closed_pipe(tmp_path):
    """The status is that of the work: an unknown robot stays 2, not 0 nor 1."""
    done = run_into_closed_pipe(["analyze", "no-such-robot"], tmp_path)
    assert done.returncode == 2 and "Traceback" not in done.stderr


def test_crosscheck_table_says_its_columns_are_relative_errors(tmp_path):
    done = subprocess.run(
        [sys.executable, "-m", "gimwatch", "crosscheck", "chain:3", "--samples", "1"],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
    )
    assert done.returncode == 0, done.stderr
    assert "columns GIM to pivots: worst relative error" in done.stdout
