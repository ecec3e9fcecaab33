"""Figures of the benchmark, drawn from the rows of its tables (measure, then plot).

Each ``draw_*`` function takes table rows, draws on ``ax`` (a new figure's axes when None)
and returns the Axes, with units on both axes; it never selects a backend or shows. Each
``plot_*`` function draws a whole figure from the rows and writes it to a PNG atomically.
`replot` redraws every figure of a benchmark folder from its committed JSON tables,
without measuring anything (``gimwatch bench --replot``).
"""

from __future__ import annotations

import io
import json
from collections.abc import Callable
from pathlib import Path

import numpy as np

from gimwatch.output.atomic import write_bytes_atomic

__all__ = [
    "FIGURES",
    "draw_accuracy_vs_kappa",
    "draw_cost_vs_n",
    "draw_denoc_cost",
    "draw_dynamics_cost",
    "draw_pareto",
    "draw_watch_cost",
    "draw_work_precision",
    "plot_accuracy_vs_kappa",
    "plot_cost_vs_n",
    "plot_denoc_cost",
    "plot_dynamics_cost",
    "plot_pareto",
    "plot_watch_cost",
    "plot_work_precision",
    "replot",
]

EPS = float(np.finfo(float).eps)
#: Below this median relative error an estimator of κ counts as exact (round-off only).
EXACT_ERROR = 1e-6


def _axes(ax, figsize=(7.0, 4.5)):
    if ax is None:
        from matplotlib.figure import Figure  # no pyplot: leaves the user's backend alone

        ax = Figure(figsize=figsize, layout="constrained").add_subplot()
    return ax


def _save(figure, path: Path) -> Path:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    return write_bytes_atomic(Path(path), buffer.getvalue())


def _one_panel(draw: Callable, rows: list[dict], path: Path, **options) -> Path:
    ax = draw(rows, **options)
    return _save(ax.figure, path)


def draw_cost_vs_n(rows: list[dict], *, ax=None):
    """Median cost per call against n, one line per method, log-log."""
    ax = _axes(ax)
    for method in dict.fromkeys(r["method"] for r in rows):
        points = sorted((r["n"], r["median_s"]) for r in rows if r["method"] == method)
        ns, seconds = zip(*points, strict=True)
        ax.loglog(ns, np.array(seconds) * 1e6, "o-", label=method, markersize=4)
    ax.set_xlabel("n, links of the paper's rod chain [-]")
    ax.set_ylabel("median time per call [µs]")
    ax.set_title("What κ, δ and their estimates cost (one BLAS thread)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_cost_vs_n(rows: list[dict], path: Path) -> Path:
    """``conditioning_cost.png``: `draw_cost_vs_n`."""
    return _one_panel(draw_cost_vs_n, rows, path)


def draw_pareto(rows: list[dict], *, exact: bool = False, ax=None):
    """Median relative error against κ vs cost per evaluation, one marker per estimator.

    ``exact`` selects the estimators whose median error is below `EXACT_ERROR`
    (round-off only), else the approximate ones: drawn apart, each group fills its axes
    instead of crowding one corner of a 1e-16…1 range.
    """
    ax = _axes(ax)
    robots = list(dict.fromkeys(r["robot"] for r in rows))
    colors = {robot: f"C{i % 10}" for i, robot in enumerate(robots)}
    groups: dict[str, list[dict]] = {}
    for row in rows:
        groups.setdefault(row["estimator"], []).append(row)
    chosen = {
        name: group
        for name, group in groups.items()
        if (np.median([r["median_rel_error"] for r in group]) < EXACT_ERROR) == exact
    }
    markers = "osD^v<>px*h"
    for i, (estimator, group) in enumerate(chosen.items()):
        for row in group:
            error = max(row["median_rel_error"], EPS)
            ax.loglog(
                row["cost_s"] * 1e6, error, markers[i % len(markers)], color=colors[row["robot"]]
            )
        ax.plot([], [], markers[i % len(markers)], color="k", label=estimator)
    for robot, color in colors.items():
        ax.plot([], [], "s", color=color, label=robot)
    ax.set_xlabel("cost per evaluation, median [µs]")
    ax.set_ylabel("median relative error against κ [-]")
    kind = "exact up to round-off" if exact else "cheap approximations"
    ax.set_title(f"Estimators of κ, {kind} (lower left is better)", fontsize="medium")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7, ncol=2)
    return ax


def plot_pareto(rows: list[dict], path: Path) -> Path:
    """``estimators_pareto.png``: approximate and exact estimators in two panels."""
    from matplotlib.figure import Figure

    figure = Figure(figsize=(12.0, 4.8), layout="constrained")
    left, right = figure.subplots(1, 2)
    draw_pareto(rows, exact=False, ax=left)
    draw_pareto(rows, exact=True, ax=right)
    return _save(figure, path)


def draw_accuracy_vs_kappa(rows: list[dict], *, ax=None):
    """Relative error of q̈ against κ for each method, with the κ·eps line."""
    ax = _axes(ax)
    kappas = np.array([r["kappa"] for r in rows])
    for i, method in enumerate(dict.fromkeys(r["method"] for r in rows)):
        points = [
            (r["kappa"], max(r["rel_error"], EPS / 10)) for r in rows if r["method"] == method
        ]
        x, y = zip(*points, strict=True)
        ax.loglog(x, y, "osD^v"[i % 5], label=method, markersize=4, alpha=0.8)
    line = np.geomspace(kappas.min(), kappas.max(), 50)
    ax.loglog(line, line * EPS, "k--", label="κ·eps")
    ax.set_xlabel("κ₂(M) [-]")
    ax.set_ylabel("relative error of q̈ vs mpmath (50 digits) [-]")
    ax.set_title("Forward-dynamics accuracy vs conditioning")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_accuracy_vs_kappa(rows: list[dict], path: Path) -> Path:
    """``accuracy_vs_kappa.png``: `draw_accuracy_vs_kappa`."""
    return _one_panel(draw_accuracy_vs_kappa, rows, path)


def draw_watch_cost(rows: list[dict], *, ax=None):
    """One watch sample's cost as a % of a bare simulation step: grouped bars, linear axis.

    Bars start at zero on a linear axis (a bar's length is its value); each bar is labelled
    with its value so that the small ones can still be read.
    """
    ax = _axes(ax)
    watches = [w for w in dict.fromkeys(r["watch"] for r in rows) if w != "none"]
    ns = sorted({r["n"] for r in rows})
    width = 0.8 / max(len(watches), 1)
    for i, watch in enumerate(watches):
        values = [
            100 * next(r["sample_vs_step"] for r in rows if r["n"] == n and r["watch"] == watch)
            for n in ns
        ]
        bars = ax.bar(np.arange(len(ns)) + i * width, values, width, label=watch)
        ax.bar_label(bars, fmt="%.3g", fontsize=7, padding=1)
    ax.set_xticks(np.arange(len(ns)) + width * (len(watches) - 1) / 2, [f"n = {n}" for n in ns])
    ax.set_xlabel("chain length [links]")
    ax.set_ylabel("one watch sample / one bare RK4+ABA step [%]")
    ax.set_title("What the watch costs (a sample every step; amortize by the sampling rate)")
    ax.grid(True, axis="y", alpha=0.3)
    ax.legend(fontsize=8)
    return ax


def plot_watch_cost(rows: list[dict], path: Path) -> Path:
    """``watch_cost.png``: `draw_watch_cost`."""
    return _one_panel(draw_watch_cost, rows, path)


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


def draw_dynamics_cost(rows: list[dict], *, ax=None):
    """Forward-dynamics cost per call against n, one line per backend, log-log."""
    ax = _axes(ax)
    _loglog_lines(rows, "backend", "call_us", ax)
    ax.set_xlabel("n, links of the paper's rod chain [-]")
    ax.set_ylabel("forward dynamics, median per call [µs]")
    ax.set_title("Dynamics backends: cost of one q̈ evaluation")
    return ax


def plot_dynamics_cost(rows: list[dict], path: Path) -> Path:
    """``dynamics_cost.png``: `draw_dynamics_cost`."""
    return _one_panel(draw_dynamics_cost, rows, path)


def draw_denoc_cost(rows: list[dict], *, ax=None):
    """DeNOC / Pinocchio time ratio per quantity against n (the rod chains ``chain:n``)."""
    ax = _axes(ax)
    _loglog_lines(rows, "quantity", "ratio", ax)
    ax.axhline(1.0, color="k", lw=0.8, ls=":")
    ax.set_xlabel("n, links of the planar rod chain chain:n [-]")
    ax.set_ylabel("DeNOC time / Pinocchio time [-]")
    ax.set_title("DeNOC (numba-compiled) against Pinocchio (C++)")
    return ax


def plot_denoc_cost(rows: list[dict], path: Path) -> Path:
    """``denoc_cost.png``: `draw_denoc_cost`."""
    return _one_panel(draw_denoc_cost, rows, path)


def draw_work_precision(rows: list[dict], n: int, *, ax=None):
    """Final-state error against wall time for the ``n``-link chain, one line per method."""
    ax = _axes(ax)
    curves = dict.fromkeys((r["simulator"], r["method"]) for r in rows if r["n"] == n)
    for k, (simulator, method) in enumerate(curves):
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
        x, y = zip(*((r["wall_s"], max(r["error_rad"], 1e-16)) for r in curve), strict=True)
        dashed = "--" if simulator == "mujoco" else "-"
        ax.loglog(
            x, y, "o" + dashed, color=f"C{k % 10}", label=f"{simulator} {method}", markersize=3
        )
    ax.axhline(1e-10, color="k", lw=0.8, ls=":")
    ax.set_xlabel("wall time [s]")
    ax.set_ylabel("final-state error, max |q − q_ref| [rad]")
    ax.set_title(f"{n}-link swinging chain")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=7)
    return ax


def plot_work_precision(rows: list[dict], path: Path) -> Path:
    """``work_precision.png``: one `draw_work_precision` panel per chain."""
    from matplotlib.figure import Figure

    chains = list(dict.fromkeys(r["n"] for r in rows))
    figure = Figure(figsize=(5.0 * len(chains), 4.5), layout="constrained")
    axes = figure.subplots(1, len(chains), squeeze=False)[0]
    for ax, n in zip(axes, chains, strict=True):
        draw_work_precision(rows, n, ax=ax)
    return _save(figure, path)


#: Every figure of a benchmark folder: PNG name → (JSON table, its writer, which rows).
FIGURES: dict[str, tuple[str, Callable[[list[dict], Path], Path], Callable[[dict], bool]]] = {
    "conditioning_cost.png": ("conditioning.json", plot_cost_vs_n, lambda r: True),
    "estimators_pareto.png": ("estimators.json", plot_pareto, lambda r: r["sweep"] == "swing"),
    "accuracy_vs_kappa.png": ("accuracy.json", plot_accuracy_vs_kappa, lambda r: True),
    "dynamics_cost.png": ("dynamics.json", plot_dynamics_cost, lambda r: True),
    "work_precision.png": ("integrators.json", plot_work_precision, lambda r: True),
    "watch_cost.png": ("watch.json", plot_watch_cost, lambda r: True),
    "denoc_cost.png": ("denoc.json", plot_denoc_cost, lambda r: True),
}


def draw_digits(rows: list[dict], *, ax=None):
    """Two panels: plain error vs κ and D^1/2-weighted error vs κ_S, one marker per solver."""
    if ax is None:
        from matplotlib.figure import Figure

        ax = Figure(figsize=(11.0, 4.5), layout="constrained").subplots(1, 2)
    solvers = list(dict.fromkeys(r["solver"] for r in rows))
    for panel, (key, error, label) in zip(
        ax,
        (
            ("kappa", "rel_error", "κ₂(M)"),
            ("kappa_equilibrated", "energy_error", "κ_S = κ₂(D^-1/2 M D^-1/2)"),
        ),
        strict=True,
    ):
        for i, solver in enumerate(solvers):
            mine = [r for r in rows if r["solver"] == solver]
            x = [r[key] for r in mine]
            y = [max(r[error], EPS / 10) for r in mine]
            panel.loglog(x, y, "osD^v"[i % 5], label=solver, markersize=4, alpha=0.7)
        values = np.array([r[key] for r in rows])
        line = np.geomspace(values.min(), values.max(), 50)
        panel.loglog(line, line * EPS, "k--", label=f"{label.split(' =')[0]}·eps")
        panel.set_xlabel(f"{label} [-]")
        panel.set_ylabel(f"{'plain' if error == 'rel_error' else 'D^1/2-weighted'} error [-]")
        panel.grid(True, which="both", alpha=0.3)
        panel.legend(fontsize=7)
    ax[0].set_title("error of q̈ = M⁻¹τ vs mpmath, against κ")
    ax[1].set_title("energy-norm error against κ_S")
    return ax


def plot_digits(rows: list[dict], path: Path) -> Path:
    """``digits.png``: `draw_digits`."""
    return _save(draw_digits(rows)[0].figure, path)


def _finite(value):
    return float("nan") if value is None else value


def replot(folder: str | Path) -> list[Path]:
    """Redraw every figure whose table is in ``folder`` from that table; measure nothing.

    Returns:
        The PNG files written (tables absent from the folder are skipped).
    """
    folder = Path(folder)
    written = []
    for png, (table, writer, keep) in FIGURES.items():
        source = folder / table
        if not source.is_file():
            continue
        rows = json.loads(source.read_text(encoding="utf-8"))["rows"]
        rows = [{k: _finite(v) for k, v in row.items()} for row in rows if keep(row)]
        if rows:
            written.append(writer(rows, folder / png))
    return written
