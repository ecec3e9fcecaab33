"""Figures of a survey: κ against δ for every robot, and one small panel per robot.

Robots are categories, not a continuous quantity: the scatter draws every robot in grey
and highlights, in categorical colours, the few where log δ tracks log κ worst (the ones a
reader should look at); the grid gives every robot its own panel. Functions take ``ax=None``
or ``fig=None``, return what they drew on, and never select a backend or show.
"""

from __future__ import annotations

import math

import numpy as np

from gimwatch.survey.run import SurveyResult

__all__ = [
    "GRID_PANELS",
    "HIGHLIGHTED",
    "OUTLIER_DECADES",
    "grid_figsize",
    "plot_kappa_vs_delta",
    "plot_kappa_vs_delta_grid",
]

#: How many robots the scatter highlights: those with the lowest Pearson r(log δ, log κ).
HIGHLIGHTED = 8
#: A point this many decades beyond the 0.5-99.5 % range of the others is left off the axes
#: (and counted in a note) rather than stretching them: one κ = 1e17 hides 60 robots' spread.
OUTLIER_DECADES = 1.0
#: The most panels the per-robot grid draws (10 rows of 6): each costs ~0.5 s of layout and
#: 0.3 Mpixel, so 2,000 robots took longer to draw than to survey. Beyond it, the panels are
#: the robots where log δ tracks log κ worst (every robot stays in the scatter and tables).
GRID_PANELS = 60


def grid_figsize(count: int) -> tuple[float, float]:
    """The size (in) of the per-robot grid: 6 panels a row, at least 6.5 in wide for the labels."""
    count = min(max(count, 1), GRID_PANELS)
    columns = min(6, count)
    return max(2.6 * columns, 6.5), 2.3 * math.ceil(count / columns) + 0.9


def _robust_limits(values: np.ndarray) -> tuple[float, float]:
    """Log-axis limits holding every point but lone outliers (see `OUTLIER_DECADES`)."""
    logs = np.log10(values[np.isfinite(values) & (values > 0)])
    if logs.size == 0:
        return 1.0, 10.0
    low, high = np.quantile(logs, [0.005, 0.995])
    kept = logs[(logs >= low - OUTLIER_DECADES) & (logs <= high + OUTLIER_DECADES)]
    low, high = kept.min(), kept.max()
    pad = 0.05 * max(high - low, 1.0)
    return 10 ** (low - pad), 10 ** (high + pad)


#: A Pearson r at or above this prints as 1.00: such a robot is never shown as tracking worst.
TRACKS_WELL = 0.995


def _joined(arrays: list[np.ndarray]) -> np.ndarray:
    """The values of ``arrays``, flattened one after the other (none: an empty array)."""
    return np.concatenate([np.ravel(a) for a in arrays]) if arrays else np.empty(0)


def _format(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:.2f}"


def _worst_tracked(result: SurveyResult, count: int) -> list:
    """The ``count`` robots with the lowest Pearson r of log δ with log κ.

    Robots whose r is undefined (δ or κ constant over the samples) are not candidates, nor
    those whose r prints as 1.00 (r >= `TRACKS_WELL`): they track κ as well as can be shown.
    """
    defined = [
        r for r in result.robots if math.isfinite(r.pearson_log) and r.pearson_log < TRACKS_WELL
    ]
    return sorted(defined, key=lambda robot: robot.pearson_log)[:count]


def plot_kappa_vs_delta(result: SurveyResult, ax=None):
    """Log-log scatter of κ against δ: all robots grey, the worst-tracked highlighted.

    The dashed line is the bound κ >= δ (Shah & Saha 2013): no point lies below it.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(8, 6), layout="constrained")
    highlighted = _worst_tracked(result, HIGHLIGHTED)
    for robot in result.robots:
        if robot not in highlighted:
            ax.scatter(robot.metrics["diagonal_ratio"], robot.metrics["kappa"], s=4, color="0.75")
    others = len(result.robots) - len(highlighted)
    if others:
        ax.scatter([], [], s=10, color="0.75", label=f"the other {others} robots")
    for k, robot in enumerate(highlighted):
        ax.scatter(
            robot.metrics["diagonal_ratio"],
            robot.metrics["kappa"],
            s=8,
            color=f"C{k % 10}",
            label=f"{robot.name} (r = {_format(robot.pearson_log)})",
        )
    delta = _joined([r.metrics["diagonal_ratio"] for r in result.robots])
    kappa = _joined([r.metrics["kappa"] for r in result.robots])
    xlim, ylim = _robust_limits(delta), _robust_limits(kappa)
    both = (min(xlim[0], ylim[0]), max(xlim[1], ylim[1]))
    ax.plot(both, both, "k--", linewidth=0.8, label="κ = δ (lower bound)")
    outside = (delta > xlim[1]) | (delta < xlim[0]) | (kappa > ylim[1]) | (kappa < ylim[0])
    if outside.any():
        worst = max(
            (r for r in result.robots if np.nanmax(r.metrics["kappa"]) > ylim[1]),
            key=lambda r: np.nanmax(r.metrics["kappa"]),
            default=None,
        )
        extreme = f"; largest κ = {np.nanmax(kappa):.2g} ({worst.name})" if worst else ""
        ax.text(
            0.99,
            0.01,
            f"{int(outside.sum())} point(s) beyond the axes{extreme}",
            transform=ax.transAxes,
            ha="right",
            va="bottom",
            fontsize=7,
        )
    ax.set(
        xscale="log",
        yscale="log",
        xlim=xlim,
        ylim=ylim,
        xlabel="diagonal ratio δ [-]",
        ylabel="condition number κ₂ [-]",
        title=f"κ against δ, {len(result.robots)} robots"
        + (
            f" (coloured: the {len(highlighted)} where log δ tracks log κ worst)"
            if highlighted
            else ""
        ),
    )
    ax.title.set_fontsize("medium")
    ax.legend(fontsize=7, loc="upper left", title="Pearson r(log δ, log κ)", title_fontsize=7)
    return ax


def plot_kappa_vs_delta_grid(result: SurveyResult, fig=None):
    """One log-log panel per robot: κ against δ, with the calibrated line κ = αδ."""
    from matplotlib.ticker import (
        FormatStrFormatter,
        LogLocator,
        MaxNLocator,
        NullFormatter,
        NullLocator,
    )

    shown = _grid_robots(result)
    count = max(len(shown), 1)
    columns = min(6, count)
    rows = math.ceil(count / columns)
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=grid_figsize(count))
    fig.set_layout_engine("constrained")
    axes = fig.subplots(rows, columns, squeeze=False)
    for ax, robot in zip(axes.flat, shown, strict=False):
        delta = robot.metrics["diagonal_ratio"]
        ax.scatter(delta, robot.metrics["kappa"], s=3, color="C0")
        line = np.array([np.nanmin(delta), np.nanmax(delta)])
        if math.isfinite(robot.alpha):
            ax.plot(line, robot.alpha * line, "k--", linewidth=0.7)
        ax.set(xscale="log", yscale="log")
        ax.autoscale_view()
        for axis in (ax.xaxis, ax.yaxis):
            low, high = axis.get_view_interval()
            if np.log10(high) - np.log10(low) >= 1.0:  # a decade or more in view
                # at most three labelled decades: no colliding ticks
                axis.set_major_locator(LogLocator(numticks=3))
                axis.set_minor_formatter(NullFormatter())
            else:  # within a decade: three plain numbers, so that no panel is left without
                axis.set_major_locator(MaxNLocator(nbins=3))
                axis.set_major_formatter(FormatStrFormatter("%.3g"))
                axis.set_minor_locator(NullLocator())
        ax.set_title(f"{robot.name} (r = {_format(robot.pearson_log)})", fontsize=7)
        ax.tick_params(which="both", labelsize=6)
    for ax in axes.flat[len(shown) :]:
        ax.set_axis_off()
    fig.supxlabel("diagonal ratio δ [-]")
    fig.supylabel("condition number κ₂ [-]")
    which = (
        "per robot"
        if len(shown) == len(result.robots)
        else f"for the {len(shown)} of {len(result.robots)} robots where log δ tracks log κ worst"
    )
    fig.suptitle(f"κ against δ {which} (dashed: κ = αδ, α at the neutral configuration)")
    return fig


def _grid_robots(result: SurveyResult) -> list:
    """Every robot, or at most `GRID_PANELS`: the worst-tracked first, then in survey order."""
    if len(result.robots) <= GRID_PANELS:
        return list(result.robots)
    chosen = _worst_tracked(result, GRID_PANELS)
    names = {id(robot) for robot in chosen}
    rest = [robot for robot in result.robots if id(robot) not in names]
    return chosen + rest[: GRID_PANELS - len(chosen)]
