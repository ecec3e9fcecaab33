"""Conditioning along a trajectory file: a CSV of configurations q, one row per sample.

The file has one row per sample and ``nq`` numeric columns in Pinocchio's q order; a first
row of column names is allowed (then the names must be the robot's coordinate names, e.g.
``shoulder_pan_joint``, or ``t`` plus them: a first ``t``/``time`` column is kept as time).
Every error names the file, the line and what is wrong. The metrics run through
`gimwatch.explain.maps.metrics_at` in chunks, as maps do.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from gimwatch.errors import InputError
from gimwatch.explain.maps import (
    CHUNK_POINTS,
    check_metrics,
    checked_configurations,
    metrics_at,
    robot_coordinates,
    run_chunks,
)
from gimwatch.metrics.analyze import choose_path
from gimwatch.survey.sweep import Task

__all__ = ["MAX_SAMPLES", "TrajectoryMetrics", "read_trajectory_csv", "trajectory_metrics"]

#: Samples a trajectory file may hold.
MAX_SAMPLES = 10_000_000
_TIME = ("t", "time", "time_s")


def _number(text: str, path: Path, line: int, column: int) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{path}:{line}", f"numbers (column {column + 1})", text) from None
    if not math.isfinite(value):
        raise InputError(f"{path}:{line}", f"finite numbers (column {column + 1})", text)
    return value


def read_trajectory_csv(
    path: str | Path, names: Sequence[str]
) -> tuple[np.ndarray | None, np.ndarray]:
    """(time or None, q array (K, nq)) from a CSV file of configurations.

    Args:
        path: The CSV file.
        names: The robot's configuration coordinate names (their count is nq).

    Raises:
        InputError: A missing or unreadable file, no rows, a row of the wrong length, a cell
            that is not a finite number, unknown column names.
    """
    path = Path(path)
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            rows = [(i + 1, row) for i, row in enumerate(csv.reader(stream)) if row]
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError("--trajectory", "a readable CSV file", str(path), hint=str(exc)) from None
    if not rows:
        raise InputError("--trajectory", "a CSV file with at least one row of q", str(path))
    header = [cell.strip() for cell in rows[0][1]]
    has_time = header[0].lower() in _TIME
    try:
        float(header[0])
    except ValueError:  # a first cell that is no number: a header row
        columns = header[1:] if has_time else header
        if columns != list(names):
            raise InputError(
                f"{path}:1",
                f"column names {', '.join(names)} (the robot's q order)",
                ", ".join(columns),
            ) from None
        rows = rows[1:]
    if not rows:
        raise InputError("--trajectory", "a CSV file with at least one row of q", str(path))
    if len(rows) > MAX_SAMPLES:
        raise InputError("--trajectory", f"at most {MAX_SAMPLES} rows", len(rows))
    width = len(names) + has_time
    values = np.empty((len(rows), width))
    for k, (line, row) in enumerate(rows):
        if len(row) != width:
            raise InputError(f"{path}:{line}", f"{width} columns", len(row))
        values[k] = [_number(cell, path, line, c) for c, cell in enumerate(row)]
    return (values[:, 0], values[:, 1:]) if has_time else (None, values)


@dataclass(frozen=True)
class TrajectoryMetrics:
    """Metrics of M at each sample of a trajectory.

    Attributes:
        robot: Robot name.
        time: Sample times from the file (s), or None (then the sample index is the axis).
        q: The configurations, (K, nq).
        path: ``crba`` or ``denoc``.
        values: Metric name -> array (K,); NaN where an interruption left samples undone.
        interrupted: Whether Ctrl-C stopped it early.
    """

    robot: str
    time: np.ndarray | None
    q: np.ndarray
    path: str
    values: dict[str, np.ndarray]
    interrupted: bool = False


def trajectory_metrics(
    spec: str,
    trajectory: str | Path,
    *,
    metrics: Sequence[str] = ("kappa", "diagonal_ratio"),
    backend: str = "auto",
    workers: int | None = 1,
    scheduler: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> TrajectoryMetrics:
    """Metrics of M(q) at every row of a trajectory CSV (see the module docstring)."""
    path = choose_path(spec, backend=backend)
    metrics = check_metrics(list(metrics), path)
    name, coordinates = robot_coordinates(spec, path)
    time, qs = read_trajectory_csv(trajectory, coordinates)
    qs = checked_configurations(spec, path, qs, name=f"q of {trajectory}")
    starts = range(0, len(qs), CHUNK_POINTS)
    tasks = [Task(metrics_at, (spec, path, qs[s : s + CHUNK_POINTS], metrics)) for s in starts]
    values, interrupted = run_chunks(
        tasks, starts, (len(qs),), metrics, workers=workers, scheduler=scheduler, progress=progress
    )
    return TrajectoryMetrics(
        robot=name,
        time=time,
        q=qs,
        path=path,
        values=values,
        interrupted=interrupted,
    )
