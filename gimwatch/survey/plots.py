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

__all__ = ["HIGHLIGHTED", "plot_kappa_vs_delta", "plot_kappa_vs_delta_grid"]

#: How many robots the scatter highlights: those with the lowest Pearson r(log δ, log κ).
HIGHLIGHTED = 8


def _format(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:.2f}"


def _worst_tracked(result: SurveyResult, count: int) -> list:
    """The ``count`` robots with the lowest Pearson r of log δ with log κ.

    Robots whose r is undefined (δ or κ constant over the samples) are not candidates.
    """
    defined = [r for r in result.robots if math.isfinite(r.pearson_log)]
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
    ax.scatter([], [], s=10, color="0.75", label=f"other {len(result.robots) - len(highlighted)}")
    for k, robot in enumerate(highlighted):
        ax.scatter(
            robot.metrics["diagonal_ratio"],
            robot.metrics["kappa"],
            s=8,
            color=f"C{k % 10}",
            label=f"{robot.name} (r = {_format(robot.pearson_log)})",
        )
    limits = [
        min([r.quantiles["diagonal_ratio"]["min"] for r in result.robots], default=1.0),
        max([r.quantiles["kappa"]["max"] for r in result.robots], default=10.0),
    ]
    ax.plot(limits, limits, "k--", linewidth=0.8, label="κ = δ (lower bound)")
    ax.set(
        xscale="log",
        yscale="log",
        xlabel="diagonal ratio δ [-]",
        ylabel="condition number κ₂ [-]",
        title=f"κ against δ, {len(result.robots)} robots "
        f"(coloured: the {len(highlighted)} where log δ tracks log κ worst)",
    )
    ax.title.set_fontsize("medium")
    ax.legend(fontsize=7, loc="upper left", title="Pearson r(log δ, log κ)", title_fontsize=7)
    return ax


def plot_kappa_vs_delta_grid(result: SurveyResult, fig=None):
    """One log-log panel per robot: κ against δ, with the calibrated line κ = αδ."""
    from matplotlib.ticker import LogLocator, NullFormatter

    count = max(len(result.robots), 1)
    columns = min(6, count)
    rows = math.ceil(count / columns)
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(2.6 * columns, 2.3 * rows + 0.6))
    fig.set_layout_engine("constrained")
    axes = fig.subplots(rows, columns, squeeze=False)
    for ax, robot in zip(axes.flat, result.robots, strict=False):
        delta = robot.metrics["diagonal_ratio"]
        ax.scatter(delta, robot.metrics["kappa"], s=3, color="C0")
        line = np.array([np.nanmin(delta), np.nanmax(delta)])
        if math.isfinite(robot.alpha):
            ax.plot(line, robot.alpha * line, "k--", linewidth=0.7)
        ax.set(xscale="log", yscale="log")
        for axis in (ax.xaxis, ax.yaxis):  # at most three labelled decades: no colliding ticks
            axis.set_major_locator(LogLocator(numticks=3))
            axis.set_minor_formatter(NullFormatter())
        ax.set_title(f"{robot.name} (r = {_format(robot.pearson_log)})", fontsize=7)
        ax.tick_params(labelsize=6)
    for ax in axes.flat[len(result.robots) :]:
        ax.set_axis_off()
    fig.supxlabel("diagonal ratio δ [-]")
    fig.supylabel("condition number κ₂ [-]   (dashed: αδ, α at the neutral configuration)")
    return fig
