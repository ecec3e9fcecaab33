"""Figures of the benchmark, drawn from the rows of its tables (measure, then plot).

Each ``plot_*`` function takes table rows and a PNG path, draws with matplotlib's Agg
backend, writes the file atomically and returns the path.
"""

from __future__ import annotations

import io
from pathlib import Path

import numpy as np

from gimwatch.output.atomic import write_bytes_atomic

__all__ = [
    "plot_accuracy_vs_kappa",
    "plot_cost_vs_n",
    "plot_denoc_cost",
    "plot_dynamics_cost",
    "plot_pareto",
    "plot_watch_cost",
    "plot_work_precision",
]

EPS = float(np.finfo(float).eps)


def _figure():
    from matplotlib.figure import Figure  # no pyplot: leaves the user's backend alone

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


def plot_watch_cost(rows: list[dict], path: Path) -> Path:
    """One watch sample's cost as a fraction of a bare simulation step, per n and watch."""
    figure = _figure()
    ax = figure.add_subplot()
    watches = [w for w in dict.fromkeys(r["watch"] for r in rows) if w != "none"]
    ns = sorted({r["n"] for r in rows})
    width = 0.8 / max(len(watches), 1)
    for i, watch in enumerate(watches):
        values = [
            next(r["sample_vs_step"] for r in rows if r["n"] == n and r["watch"] == watch)
            for n in ns
        ]
        ax.bar(np.arange(len(ns)) + i * width, np.array(values) * 100, width, label=watch)
    ax.set_xticks(np.arange(len(ns)) + width * (len(watches) - 1) / 2, [f"n = {n}" for n in ns])
    ax.set_yscale("log")
    ax.set_ylabel("one watch sample / one bare RK4+ABA step (%)")
    ax.set_title("What the watch costs (a sample every step; amortize by the sampling rate)")
    ax.grid(True, axis="y", which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return _save(figure, path)


def _loglog_lines(rows: list[dict], series: str, value: str, ax) -> None:
    """One log-log line of ``value`` against n per distinct ``series`` (finite points only)."""
    for name in dict.fromkeys(r[series] for r in rows):
        points = sorted(
            (r["n"], r[value]) for r in rows if r[series] == name and np.isfinite(r[value])
        )
        if points:
            ns, values = zip(*points, strict=True)
            ax.loglog(ns, values, "o-", label=name, markersize=4)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)


def plot_dynamics_cost(rows: list[dict], path: Path) -> Path:
    """Forward-dynamics cost per call against n, one line per backend, log-log."""
    figure = _figure()
    ax = figure.add_subplot()
    _loglog_lines(rows, "backend", "call_us", ax)
    ax.set_xlabel("n (links of the paper chain)")
    ax.set_ylabel("forward dynamics, median µs per call")
    ax.set_title("Dynamics backends: cost of one q̈ evaluation")
    return _save(figure, path)


def plot_denoc_cost(rows: list[dict], path: Path) -> Path:
    """DeNOC / Pinocchio time ratio per quantity against n."""
    figure = _figure()
    ax = figure.add_subplot()
    _loglog_lines(rows, "quantity", "ratio", ax)
    ax.set_xlabel("n (links, spatial chain)")
    ax.set_ylabel("DeNOC time / Pinocchio time")
    ax.set_title("DeNOC against Pinocchio (C++)")
    return _save(figure, path)


def plot_work_precision(rows: list[dict], path: Path) -> Path:
    """Final-state error against wall time, one panel per chain, one line per method."""
    from matplotlib.figure import Figure

    chains = list(dict.fromkeys(r["n"] for r in rows))
    figure = Figure(figsize=(5.0 * len(chains), 4.5), layout="constrained")
    axes = figure.subplots(1, len(chains), squeeze=False)[0]
    styles = {}
    for ax, n in zip(axes, chains, strict=True):
        curves = dict.fromkeys((r["simulator"], r["method"]) for r in rows if r["n"] == n)
        for simulator, method in curves:
            curve = [
                r
                for r in rows
                if (r["n"], r["simulator"], r["method"]) == (n, simulator, method)
                and np.isfinite(r["error_rad"])
            ]
            if not curve:
                continue
            # in order of the error control (loosest tolerance or largest step first),
            # not of the measured (noisy) wall time
            curve.sort(key=lambda r: -(r["rtol"] if np.isfinite(r["rtol"]) else r["dt_s"]))
            points = [(r["wall_s"], max(r["error_rad"], 1e-16)) for r in curve]
            label = f"{simulator} {method}"
            color = styles.setdefault(label, f"C{len(styles) % 10}")
            x, y = zip(*points, strict=True)
            dashed = "--" if simulator == "mujoco" else "-"
            ax.loglog(x, y, "o" + dashed, color=color, label=label, markersize=3)
        ax.axhline(1e-10, color="k", lw=0.8, ls=":")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("final-state error, max |q - q_ref| (rad)")
        ax.set_title(f"{n}-link swinging chain")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    return _save(figure, path)
