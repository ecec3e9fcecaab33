"""Figures of the benchmark, drawn from the rows of its tables (measure, then plot).

Each ``plot_*`` function takes table rows and a PNG path, draws with matplotlib's Agg
backend, writes the file atomically and returns the path.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from gimwatch.results import write_bytes_atomic

__all__ = ["plot_accuracy_vs_kappa", "plot_cost_vs_n", "plot_pareto"]

EPS = float(np.finfo(float).eps)


def _figure():
    import matplotlib

    matplotlib.use("Agg", force=False)
    from matplotlib.figure import Figure

    return Figure(figsize=(7.0, 4.5), layout="constrained")


def _save(figure, path: Path) -> Path:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return write_bytes_atomic(path, buffer.getvalue())


def plot_cost_vs_n(rows: list[dict], path: Path) -> Path:
    """Median cost per call against n, one line per method, log-log."""
    figure = _figure()
    ax = figure.add_subplot()
    for method in dict.fromkeys(r["method"] for r in rows):
        points = sorted((r["n"], r["median_s"]) for r in rows if r["method"] == method)
        ns, seconds = zip(*points, strict=True)
        ax.loglog(ns, np.array(seconds) * 1e6, "o-", label=method, markersize=4)
    ax.set_xlabel("n (links of the paper chain)")
    ax.set_ylabel("median time per call (µs)")
    ax.set_title("What κ, δ and their estimates cost (one BLAS thread)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)


def plot_pareto(rows: list[dict], path: Path) -> Path:
    """Estimator error (median relative error vs κ) against cost per evaluation."""
    figure = _figure()
    ax = figure.add_subplot()
    estimators = list(dict.fromkeys(r["estimator"] for r in rows))
    markers = "osD^v<>px*h"
    robots = list(dict.fromkeys(r["robot"] for r in rows))
    colors = {robot: f"C{i % 10}" for i, robot in enumerate(robots)}
    for i, estimator in enumerate(estimators):
        for row in (r for r in rows if r["estimator"] == estimator):
            error = max(row["median_rel_error"], EPS)
            ax.loglog(
                row["cost_s"] * 1e6, error, markers[i % len(markers)], color=colors[row["robot"]]
            )
    for i, estimator in enumerate(estimators):
        ax.plot([], [], markers[i % len(markers)], color="k", label=estimator)
    for robot, color in colors.items():
        ax.plot([], [], "s", color=color, label=robot)
    ax.set_xlabel("cost per evaluation (µs, median)")
    ax.set_ylabel("median relative error against κ")
    ax.set_title("Estimators of κ: error vs cost (lower left is better)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return _save(figure, path)


def plot_accuracy_vs_kappa(rows: list[dict], path: Path) -> Path:
    """Relative error of q̈ against κ for each method, with the κ·eps line."""
    figure = _figure()
    ax = figure.add_subplot()
    kappas = np.array([r["kappa"] for r in rows])
    for i, method in enumerate(dict.fromkeys(r["method"] for r in rows)):
        points = [
            (r["kappa"], max(r["rel_error"], EPS / 10)) for r in rows if r["method"] == method
        ]
        x, y = zip(*points, strict=True)
        ax.loglog(x, y, "osD^v"[i % 5], label=method, markersize=4, alpha=0.8)
    line = np.geomspace(kappas.min(), kappas.max(), 50)
    ax.loglog(line, line * EPS, "k--", label="κ·eps")
    ax.set_xlabel("κ₂(M)")
    ax.set_ylabel("relative error of q̈ (vs mpmath, 50 digits)")
    ax.set_title("Forward-dynamics accuracy vs conditioning")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)
