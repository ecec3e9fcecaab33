"""Conditioning maps and trajectory metrics on disk and on paper: heat maps, line plots, CSV.

``write_map`` writes ``map.csv`` (one row per grid point: both joints and every metric),
``map.json`` (axes, units, base configuration) and one ``map_<metric>.png`` heat map per
metric; ``write_trajectory_metrics`` writes ``trajectory.csv`` and ``trajectory.png``. All
go through a `ResultsFolder`: a failed or interrupted run
never leaves half a folder, and never replaces a good one.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from gimwatch.explain.maps import ConditioningMap
from gimwatch.explain.trajectory import TrajectoryMetrics
from gimwatch.output.atomic import write_bytes_atomic, write_json_atomic, write_text_atomic
from gimwatch.output.folders import ResultsFolder

__all__ = ["plot_map", "plot_trajectory_metrics", "write_map", "write_trajectory_metrics"]

#: How each metric is labelled on a figure.
LABELS = {
    "kappa": "κ = λmax/λmin",
    "diagonal_ratio": "δ = max diag M / min diag M",
    "kappa_equilibrated": "κ_S = κ(D^-1/2 M D^-1/2)",
}


def plot_map(result: ConditioningMap, metric: str = "kappa", *, ax=None):
    """Heat map of one metric over the two joints, log colour scale; returns the Axes."""
    from matplotlib.colors import LogNorm

    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6, 5), layout="constrained")
    values = result.values[metric]
    finite = values[np.isfinite(values) & (values > 0)]
    norm = LogNorm(finite.min(), finite.max()) if finite.size and finite.min() > 0 else None
    mesh = ax.pcolormesh(result.x, result.y, values, norm=norm, shading="nearest")
    ax.figure.colorbar(mesh, ax=ax, label=LABELS.get(metric, metric))
    ax.set_xlabel(f"{result.joints[0]} ({result.units[0]})")
    ax.set_ylabel(f"{result.joints[1]} ({result.units[1]})")
    ax.set_title(f"{result.robot}: {metric}, other joints fixed")
    return ax


def plot_trajectory_metrics(result: TrajectoryMetrics, *, ax=None):
    """Each metric against time (or sample index), log scale; returns the Axes."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(7, 4), layout="constrained")
    t = np.arange(len(result.q)) if result.time is None else result.time
    for metric, values in result.values.items():
        ax.plot(t, values, label=LABELS.get(metric, metric))
    ax.set_yscale("log")
    ax.set_xlabel("sample" if result.time is None else "t (s)")
    ax.set_ylabel("metric (dimensionless)")
    ax.set_title(f"{result.robot} along the trajectory")
    ax.legend()
    return ax


def _png(fig) -> bytes:
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=110)
    return buffer.getvalue()


def _csv(header: list[str], columns: list[np.ndarray]) -> str:
    lines = [",".join(header)]
    for row in np.column_stack(columns):
        lines.append(",".join(repr(float(x)) for x in row))
    return "\n".join(lines) + "\n"


def write_map(result: ConditioningMap, output: str | Path) -> Path:
    """Write map.csv, map.json and a heat map per metric into ``output``; returns map.csv."""
    from matplotlib.figure import Figure

    X, Y = np.meshgrid(result.x, result.y)
    metrics = list(result.values)
    header = [f"{result.joints[0]}_{result.units[0]}", f"{result.joints[1]}_{result.units[1]}"]
    columns = [X.ravel(), Y.ravel()] + [result.values[m].ravel() for m in metrics]
    with ResultsFolder(output, writer="map") as folder:
        staging = folder.staging
        assert staging is not None  # made on entering the block
        write_text_atomic(staging / "map.csv", _csv(header + metrics, columns))
        record = {
            "robot": result.robot,
            "joints": list(result.joints),
            "units": list(result.units),
            "grid": [len(result.x), len(result.y)],
            "range": [[result.x[0], result.x[-1]], [result.y[0], result.y[-1]]],
            "base_q": result.base_q.tolist(),
            "path": result.path,
            "interrupted": result.interrupted,
            "max": {m: float(np.nanmax(v)) for m, v in result.values.items()},
            "min": {m: float(np.nanmin(v)) for m, v in result.values.items()},
        }
        write_json_atomic(staging / "map.json", record)
        for metric in metrics:
            fig = Figure(figsize=(6, 5), layout="constrained")
            plot_map(result, metric, ax=fig.subplots())
            write_bytes_atomic(staging / f"map_{metric}.png", _png(fig))
        folder.commit()
    return Path(output) / "map.csv"


def write_trajectory_metrics(result: TrajectoryMetrics, output: str | Path) -> Path:
    """Write trajectory.csv and trajectory.png into ``output``; returns trajectory.csv."""
    from matplotlib.figure import Figure

    if result.time is None:
        first_name, first = "sample", np.arange(len(result.q), dtype=float)
    else:
        first_name, first = "t_s", result.time
    metrics = list(result.values)
    text = _csv([first_name, *metrics], [first] + [result.values[m] for m in metrics])
    with ResultsFolder(output, writer="map") as folder:
        staging = folder.staging
        assert staging is not None  # made on entering the block
        write_text_atomic(staging / "trajectory.csv", text)
        fig = Figure(figsize=(7, 4), layout="constrained")
        plot_trajectory_metrics(result, ax=fig.subplots())
        write_bytes_atomic(staging / "trajectory.png", _png(fig))
        folder.commit()
    return Path(output) / "trajectory.csv"
