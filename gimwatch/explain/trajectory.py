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
    checked_configurations,
    metrics_at,
    robot_coordinates,
    run_chunks,
)
from gimwatch.metrics.analyze import RobotLike, choose_path, spec_of
from gimwatch.survey.sweep import Task

__all__ = [
    "EXTRA_COLUMNS",
    "MAX_LINE_CHARS",
    "MAX_SAMPLES",
    "TrajectoryMetrics",
    "max_columns",
    "read_trajectory_csv",
    "trajectory_metrics",
]

#: Samples a trajectory file may hold.
MAX_SAMPLES = 10_000_000
#: Characters a line may hold per column (a float printed by NumPy takes at most 24).
MAX_LINE_CHARS = 64
#: Columns beyond t, q and v a line may hold (energy, watched metrics of a saved series).
EXTRA_COLUMNS = 64
_BLOCK = 65536  # rows stored per block while the file streams
_TIME = ("t", "time", "time_s")


def _number(text: str, path: Path, line: int, column: int) -> float:
    try:
        value = float(text)
    except ValueError:
        raise InputError(f"{path}:{line}", f"numbers (column {column + 1})", text) from None
    if not math.isfinite(value):
        raise InputError(f"{path}:{line}", f"finite numbers (column {column + 1})", text)
    return value


def _lines(stream, path: Path, width: int):
    """The file's lines, each refused past `MAX_LINE_CHARS` per column before it is kept."""
    limit = MAX_LINE_CHARS * max(width, 1)
    line = 0
    while True:
        text = stream.readline(limit + 1)
        if not text:
            return
        line += 1
        if len(text) > limit:
            raise InputError(f"{path}:{line}", f"a line of at most {limit} characters", "longer")
        yield text


def max_columns(nq: int) -> int:
    """Columns a trajectory line may hold: simulate's t, q and v plus `EXTRA_COLUMNS`."""
    return 3 * nq + EXTRA_COLUMNS


def read_trajectory_csv(
    path: str | Path, names: Sequence[str]
) -> tuple[np.ndarray | None, np.ndarray]:
    """(time or None, q array (K, nq)) from a CSV file of configurations.

    The file is streamed: the row limit (`MAX_SAMPLES`) and the line length are checked as
    rows arrive, before more is read, and rows are stored as floats in blocks.

    Args:
        path: The CSV file.
        names: The robot's configuration coordinate names (their count is nq).

    Raises:
        InputError: A missing or unreadable file, no rows, more than `MAX_SAMPLES` rows, a
            line too long, a row of the wrong length, a cell that is not a finite number,
            unknown column names.
    """
    path = Path(path)
    names = list(names)
    blocks: list[np.ndarray] = []
    count, layout = 0, None
    try:
        with path.open(newline="", encoding="utf-8") as stream:
            reader = csv.reader(_lines(stream, path, max_columns(len(names))))
            for row in reader:
                if not row:
                    continue
                line = reader.line_num
                if layout is None:
                    layout = _layout(row, names, path)
                    if layout.header:
                        continue
                if count == MAX_SAMPLES:
                    raise InputError("path", f"at most {MAX_SAMPLES} rows", f"more ({path})")
                if len(row) != layout.width:
                    raise InputError(f"{path}:{line}", f"{layout.width} columns", len(row))
                if count % _BLOCK == 0:
                    blocks.append(np.empty((_BLOCK, len(layout.columns))))
                blocks[-1][count % _BLOCK] = [
                    _number(row[c], path, line, c) for c in layout.columns
                ]
                count += 1
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError("path", "a readable CSV file", str(path), hint=str(exc)) from None
    if count == 0 or layout is None:
        raise InputError("path", "a CSV file with at least one row of q", str(path))
    values = np.concatenate(blocks)[:count] if len(blocks) > 1 else blocks[0][:count]
    return (values[:, 0], values[:, 1:]) if layout.time else (None, values)


@dataclass(frozen=True)
class _Layout:
    """Which cells of a row are read: the time (first, if ``time``) and q, of ``width``."""

    header: bool
    columns: list[int]
    width: int
    time: bool


def _layout(row: list[str], names: list[str], path: Path) -> _Layout:
    """The layout of a file from its first row (a header row when its first cell is no number).

    Two header layouts: bare coordinate names (``t`` first optionally), or ``q:<name>`` columns
    as ``simulate``'s trajectory.csv and a watch's saved series (``to_dataframe``) have them;
    other columns there (``v:<name>``, energy, watched metrics) are left out.
    """
    header = [cell.strip() for cell in row]
    try:
        float(header[0])
        return _Layout(False, list(range(len(names))), len(names), False)
    except ValueError:  # a first cell that is no number: a header row
        pass
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
    time_columns = [] if time_column is None else [time_column]
    return _Layout(True, time_columns + q_columns, len(header), time_column is not None)


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
    spec: RobotLike,
    trajectory: str | Path,
    *,
    metrics: Sequence[str] = ("kappa", "diagonal_ratio"),
    backend: str = "auto",
    workers: int | None = 1,
    scheduler: str | None = None,
    progress: Callable[[float], None] | None = None,
) -> TrajectoryMetrics:
    """Metrics of M(q) at every row of a trajectory CSV (see the module docstring).

    ``spec`` is a `Robot`, a `RobotSpec` or a robot's text (parsed and loaded once).
    """
    spec = spec_of(spec)
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
