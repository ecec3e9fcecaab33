"""Conditioning along a trajectory file: a CSV of configurations q, one row per sample.

The file has one row per sample and ``nq`` numeric columns in Pinocchio's q order; a first
row of column names is allowed (then the names must be the robot's coordinate names, e.g.
``shoulder_pan_joint``, or ``t`` plus them: a first ``t``/``time`` column is kept as time).
``simulate``'s trajectory.csv is read as it is: its ``q:<name>`` columns are the q, ``t`` the
time, and its ``v:<name>`` columns (or a watch's metric columns) are left out.
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
    try:
        float(header[0])
    except ValueError:  # a first cell that is no number: a header row
        return _read_named_columns(path, header, rows[1:], list(names))
    if len(rows) > MAX_SAMPLES:
        raise InputError("--trajectory", f"at most {MAX_SAMPLES} rows", len(rows))
    return None, _values(path, rows, range(len(names)), len(names))


def _read_named_columns(
    path: Path, header: list[str], rows: list, names: list[str]
) -> tuple[np.ndarray | None, np.ndarray]:
    """The time and q columns of a CSV with a header row.

    Two layouts: bare coordinate names (``t`` first optionally), or ``q:<name>`` columns as
    ``simulate``'s trajectory.csv and a watch's saved series (``to_dataframe``) have them; other
    columns there (``v:<name>``, energy, watched metrics) are left out.
    """
    time_column = next((i for i, h in enumerate(header) if h.lower() in _TIME), None)
    prefixed = [i for i, h in enumerate(header) if h.startswith("q:")]
    if prefixed:
        given = [header[i].removeprefix("q:") for i in prefixed]
        positional = [f"q{i}" for i in range(len(names))]  # simulate's names when nq != nv
        if given not in (names, positional):
            raise InputError(
                f"{path}:1",
                f"q:<name> columns {', '.join(names)} (the robot's q order)",
                ", ".join(header[i] for i in prefixed),
            )
        q_columns = prefixed
    else:
        columns = [h for i, h in enumerate(header) if i != time_column]
        if time_column not in (None, 0) or columns != names:
            raise InputError(
                f"{path}:1",
                f"column names {', '.join(names)} (the robot's q order) or q:<name> columns",
                ", ".join(header),
            )
        q_columns = [i for i in range(len(header)) if i != time_column]
    if not rows:
        raise InputError("--trajectory", "a CSV file with at least one row of q", str(path))
    if len(rows) > MAX_SAMPLES:
        raise InputError("--trajectory", f"at most {MAX_SAMPLES} rows", len(rows))
    wanted = ([time_column] if time_column is not None else []) + q_columns
    values = _values(path, rows, wanted, len(header))
    if time_column is None:
        return None, values
    return values[:, 0], values[:, 1:]


def _values(path: Path, rows: list, columns: Sequence[int], width: int) -> np.ndarray:
    """The numbers in ``columns`` of every row, each row ``width`` cells long."""
    values = np.empty((len(rows), len(columns)))
    for k, (line, row) in enumerate(rows):
        if len(row) != width:
            raise InputError(f"{path}:{line}", f"{width} columns", len(row))
        values[k] = [_number(row[c], path, line, c) for c in columns]
    return values


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
