"""Results as pandas DataFrames (``pip install 'gimwatch[pandas]'``).

pandas is optional: it is imported when a ``to_dataframe()`` is called, and its absence is
an [`InputError`][gimwatch.errors.InputError] that says how to install it. Column names follow the
CSV files of a results folder (``trajectory.csv``: ``t``, ``q:<name>``, ``v:<name>``;
``watch.csv``: the metric names), so a DataFrame and a CSV read back agree.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from gimwatch.errors import InputError

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["require_pandas", "survey_frame", "trajectory_frame", "watch_frame"]


def require_pandas() -> Any:
    """Import pandas, or say how to install it.

    Raises:
        InputError: pandas is not installed.
    """
    try:
        import pandas
    except ImportError:
        raise InputError(
            "to_dataframe()",
            "usable with pandas installed",
            "pandas missing",
            hint="pip install 'gimwatch[pandas]'",
        ) from None
    return pandas


def trajectory_frame(
    t: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    *,
    q_names: list[str],
    v_names: list[str],
    energy: np.ndarray | None,
    watch: dict[str, np.ndarray],
) -> pd.DataFrame:
    """One row per sample: ``t``, ``q:<name>``, ``v:<name>``, ``energy``, watched metrics.

    Watched metrics sampled at the same times as the state (``watch_t`` equal to ``t``) become
    columns named after the metric; vector metrics (eigenvalues, diagonal) are spread into
    ``<metric>:<k>``. A watch sampled on other times is left out (see `watch_frame`).
    """
    pandas = require_pandas()
    columns: dict[str, np.ndarray] = {"t": np.asarray(t)}
    for name, values in zip(q_names, np.asarray(q).T, strict=True):
        columns[f"q:{name}"] = values
    for name, values in zip(v_names, np.asarray(v).T, strict=True):
        columns[f"v:{name}"] = values
    if energy is not None:
        columns["energy"] = np.asarray(energy)
    watch_t = watch.get("watch_t")
    if watch_t is not None and np.array_equal(watch_t, columns["t"]):
        columns.update(_watch_columns(watch))
    return pandas.DataFrame(columns)


def watch_frame(watch: dict[str, np.ndarray]) -> pd.DataFrame:
    """One row per watch sample: ``t`` and the watched metrics."""
    pandas = require_pandas()
    return pandas.DataFrame({"t": np.asarray(watch.get("watch_t", [])), **_watch_columns(watch)})


def _watch_columns(watch: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
    columns = {}
    for key, values in watch.items():
        if key == "watch_t":
            continue
        name, values = key.removeprefix("watch_"), np.asarray(values)
        if values.ndim == 1:
            columns[name] = values
        else:
            for k in range(values.shape[1]):
                columns[f"{name}:{k}"] = values[:, k]
    return columns


def survey_frame(robots: Any) -> pd.DataFrame:
    """One row per (robot, sample): robot, nv, base, sample, and every per-sample metric.

    ``*_dof`` metrics (coordinate indices) are given as coordinate names.
    """
    pandas = require_pandas()
    frames = []
    for robot in robots:
        columns: dict[str, Any] = {
            "robot": robot.name,
            "nv": robot.nv,
            "base": "floating" if robot.floating else "fixed",
            "sample": np.asarray(robot.sample_index),
        }
        for key, values in robot.metrics.items():
            values = np.asarray(values)
            if key.endswith("_dof"):
                values = np.asarray(robot.dof_names, dtype=object)[values.astype(int)]
            columns[key] = values
        frames.append(pandas.DataFrame(columns))
    if not frames:
        return pandas.DataFrame(columns=["robot", "nv", "base", "sample"])
    return pandas.concat(frames, ignore_index=True)
