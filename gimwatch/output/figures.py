"""Matplotlib figures of a watched run, in the spirit of Shah & Saha (2013), Figs. 2–5.

Every function draws on ``ax`` (a new figure's axes when None), returns the Axes and
never calls ``show()``. Import matplotlib with a non-interactive backend (Agg) in scripts.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from gimwatch.joint_kinds import JointKind, joint_kind, length_positions

__all__ = [
    "MAX_LINES",
    "animate_chain",
    "joint_coordinate_units",
    "plot_delta",
    "plot_diagonal",
    "plot_eigenvalues",
    "plot_energy",
    "plot_joint_angles",
    "plot_kappa_and_delta",
    "plot_kappa_and_scaled",
    "plot_pivot_ratios",
    "plot_watch",
]


#: Above this many series a plot draws their envelope (min, median, max) and a few named
#: members instead of one overlapping line each.
MAX_LINES = 12
#: Line style of a joint coordinate by unit, so that one axis can carry rad and m apart.
_UNIT_STYLES = {"rad": "-", "m": "--", "-": ":"}


def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    return ax


def _legend_beside(ax, **options) -> None:
    """The legend to the right of the axes, off the data (many series would cover it)."""
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), borderaxespad=0.0, **options)


def _series(ax, t, values, labels, *, plot=None, style="-"):
    """One line per column of ``values``, or their envelope when there are too many.

    Returns whether the columns were drawn one by one (so a legend can name them).
    """
    plot = plot or ax.plot
    values = np.asarray(values)
    if values.shape[1] <= MAX_LINES:
        for i in range(values.shape[1]):
            plot(t, values[:, i], style, label=labels[i])
        return True
    low, middle, high = np.nanpercentile(values, [0, 50, 100], axis=1)
    ax.fill_between(t, low, high, alpha=0.25, label=f"all {values.shape[1]}: min … max")
    plot(t, middle, style, color="k", lw=1, label="median over all")
    for i in sorted({0, values.shape[1] // 2, values.shape[1] - 1}):
        plot(t, values[:, i], style, lw=0.9, label=labels[i])
    return True


def plot_eigenvalues(t: npt.ArrayLike, eigenvalues: npt.ArrayLike, *, ax=None):
    """λ_i(M) over time (Fig. 2a), largest first in the legend, log scale.

    More than `MAX_LINES` eigenvalues are drawn as their envelope plus λmax, the
    middle one and λmin.
    """
    ax = _axes(ax)
    values = np.asarray(eigenvalues)[:, ::-1]  # largest first
    labels = [f"λ{i + 1}" for i in range(values.shape[1])]
    _series(ax, t, values, labels, plot=ax.semilogy)
    ax.set(xlabel="time [s]", ylabel="eigenvalue of M [kg·m²]", title="Eigenvalues of the GIM")
    _legend_beside(ax, fontsize="small")
    return ax


def plot_diagonal(t: npt.ArrayLike, diagonal: npt.ArrayLike, *, names=None, ax=None):
    """M_ii over time (Fig. 2b), log scale, each line named by its joint (velocity coordinate).

    ``names`` are the robot's velocity-coordinate names (`Robot.dof_names`, one per M_ii);
    without them the lines are M_11, M_22, ...
    """
    ax = _axes(ax)
    values = np.asarray(diagonal)
    if names is not None and len(names) != values.shape[1]:
        raise ValueError(f"{len(names)} names for {values.shape[1]} diagonal elements")
    labels = (
        [f"M_ii of {n}" for n in names]
        if names is not None
        else [f"M_{i + 1}{i + 1}" for i in range(values.shape[1])]
    )
    _series(ax, t, values, labels, plot=ax.semilogy)
    ax.set(
        xlabel="time [s]", ylabel="diagonal element M_ii [kg·m² or kg]", title="Diagonal elements"
    )
    _legend_beside(ax, fontsize="small")
    return ax


def plot_kappa_and_delta(
    t: npt.ArrayLike, kappa: npt.ArrayLike, delta: npt.ArrayLike, *, label: str = "", ax=None
):
    """κ₂ and the diagonal ratio δ over time, each divided by its value at t = 0 (Figs. 2c–d, 3).

    δ is 40–80x below κ for the paper's chains; normalised, both start at 1 and the reader
    sees whether δ follows κ's trend. The t = 0 values are given in the legend.
    """
    ax = _axes(ax)
    kappa, delta = np.asarray(kappa, dtype=float), np.asarray(delta, dtype=float)
    prefix = f"{label}: " if label else ""
    (line,) = ax.semilogy(t, kappa / kappa[0], label=f"{prefix}κ₂ / {kappa[0]:.3g}")
    ax.semilogy(
        t, delta / delta[0], "--", color=line.get_color(), label=f"{prefix}δ / {delta[0]:.3g}"
    )
    ax.set(
        xlabel="time [s]",
        ylabel="value / value at t = 0 [-]",
        title="Condition number and diagonal ratio, relative to t = 0",
    )
    ax.legend(fontsize="small")
    return ax


def plot_delta(t: npt.ArrayLike, delta: npt.ArrayLike, *, threshold=None, label: str = "", ax=None):
    """The watched diagonal ratio δ = max M_ii / min M_ii over time, log scale, with the alarm."""
    ax = _axes(ax)
    ax.semilogy(t, delta, label=f"{label}: δ" if label else "δ")
    if threshold is not None:
        ax.axhline(threshold, color="C3", lw=0.8, ls=":", label=f"alarm at {threshold:.3g}")
    ax.set(xlabel="time [s]", ylabel="δ = max M_ii / min M_ii [-]", title="Diagonal ratio")
    ax.legend(fontsize="small")
    return ax


def plot_pivot_ratios(
    t: npt.ArrayLike,
    forward: npt.ArrayLike,
    backward: npt.ArrayLike | None = None,
    kappa: npt.ArrayLike | None = None,
    *,
    label: str = "",
    ax=None,
):
    """Pivot ratios of Gaussian elimination over time, with κ₂ for comparison (Fig. 4)."""
    ax = _axes(ax)
    prefix = f"{label}: " if label else ""
    ax.semilogy(t, forward, label=f"{prefix}pivot ratio (LDLᵀ)")
    if backward is not None:
        ax.semilogy(t, backward, ":", label=f"{prefix}pivot ratio (UDUᵀ)")
    if kappa is not None:
        ax.semilogy(t, kappa, "--", label=f"{prefix}κ₂")
    ax.set(xlabel="time [s]", ylabel="ratio [-]", title="Pivot ratios")
    ax.legend(fontsize="small")
    return ax


def plot_kappa_and_scaled(
    t: npt.ArrayLike, kappa: npt.ArrayLike, scaled: npt.ArrayLike, *, label: str = "", ax=None
):
    """κ₂ and the scaled diagonal ratio αδ (Eq. 15) over time (Fig. 5), log scale."""
    ax = _axes(ax)
    prefix = f"{label}: " if label else ""
    (line,) = ax.semilogy(t, kappa, label=f"{prefix}κ₂")
    ax.semilogy(t, scaled, "--", color=line.get_color(), label=f"{prefix}αδ")
    ax.set(
        xlabel="time [s]",
        ylabel="κ₂ and αδ [-]",
        title="Condition number and scaled diagonal ratio",
    )
    ax.legend(fontsize="small")
    return ax


def plot_energy(t: npt.ArrayLike, energy: npt.ArrayLike, *, ax=None):
    """E(t) - E(0) (J), the energy drift of a conservative run."""
    ax = _axes(ax)
    energy = np.asarray(energy)
    ax.plot(t, energy - energy[0])
    ax.set(xlabel="time [s]", ylabel="E(t) − E(0) [J]", title="Energy drift")
    return ax


def joint_coordinate_units(model) -> tuple[list[str], list[str]]:
    """(name, unit) of each configuration coordinate q_i of a Pinocchio ``model``.

    Revolute joints give rad, prismatic ones m; a continuous joint's (cos, sin) and a
    free-flyer's quaternion are dimensionless ("-"), its position in m.
    """
    names, units = [], []
    for joint, name in zip(model.joints[1:], model.names[1:], strict=True):
        kind = joint_kind(joint)
        if joint.nq == 1:
            names.append(name)
            units.append("m" if length_positions(joint) else "rad")
        elif kind is JointKind.FREE_FLYER:
            names += [f"{name}.{c}" for c in ("x", "y", "z", "qx", "qy", "qz", "qw")]
            units += ["m"] * 3 + ["-"] * 4
        else:
            names += [f"{name}.{i}" for i in range(joint.nq)]
            units += ["-"] * joint.nq
    return names, units


def plot_joint_angles(t: npt.ArrayLike, q: npt.ArrayLike, *, names=None, units=None, ax=None):
    """Joint coordinates over time, named, with one line style per unit (rad, m, -).

    Args:
        t: Sample times (s), shape (K,).
        q: Joint coordinates, shape (K, nq).
        names: Coordinate names (default q1, q2, ...).
        units: Unit of each coordinate, "rad", "m" or "-" (default all "rad");
            `joint_coordinate_units` gives both from a Pinocchio model.
        ax: Axes to draw on (a new figure's when None).
    """
    ax = _axes(ax)
    q = np.asarray(q)
    names = list(names) if names is not None else [f"q{i + 1}" for i in range(q.shape[1])]
    units = list(units) if units is not None else ["rad"] * q.shape[1]
    present = list(dict.fromkeys(units))
    for unit in present:
        columns = [i for i, u in enumerate(units) if u == unit]
        _series(ax, t, q[:, columns], [names[i] for i in columns], style=_UNIT_STYLES[unit])
    ylabel = ", ".join(
        f"{'solid' if u == 'rad' else 'dashed' if u == 'm' else 'dotted'} [{u}]" for u in present
    )
    ax.set(
        xlabel="time [s]",
        ylabel=f"joint coordinate [{present[0]}]"
        if len(present) == 1
        else f"joint coordinate: {ylabel}",
        title=f"Joint coordinates ({q.shape[1]})",
    )
    _legend_beside(ax, fontsize="small")
    return ax


def plot_watch(
    t: npt.ArrayLike,
    series: dict[str, npt.ArrayLike],
    *,
    alarm_metric: str | None = None,
    threshold: float | None = None,
    ax=None,
):
    """Watched scalar metrics over time on one log axis, with the alarm threshold (`Watch.plot`).

    Args:
        t: Sample times (s), shape (K,).
        series: Metric name -> values, shape (K,) each (condition-number scale, [-]).
        alarm_metric: The metric the threshold applies to (named in the legend).
        threshold: The alarm threshold, drawn as a dotted line; None: no line.
        ax: Axes to draw on (a new figure's when None).
    """
    ax = _axes(ax)
    for name, values in series.items():
        ax.semilogy(t, values, label=name)
    if threshold is not None:
        ax.axhline(
            threshold, color="C3", lw=0.8, ls=":", label=f"alarm: {alarm_metric} > {threshold:.3g}"
        )
    ax.set(xlabel="time [s]", ylabel="metric value [-]", title="Watched conditioning metrics")
    ax.legend(fontsize="small")
    return ax


def animate_chain(
    t: npt.ArrayLike,
    joint_xy: npt.ArrayLike,
    kappa: npt.ArrayLike,
    *,
    title: str = "",
    fig=None,
):
    """A planar chain swinging, coloured by κ₂ on a log scale; returns a FuncAnimation.

    Args:
        t: Frame times (s), shape (K,).
        joint_xy: Joint and tip positions in the plane of motion, shape (K, n + 1, 2).
        kappa: κ₂ at each frame, shape (K,).
        title: Figure title.
        fig: The (empty) figure to draw on; None: a new pyplot figure (the caller closes it).
    """
    import matplotlib
    from matplotlib.animation import FuncAnimation
    from matplotlib.cm import ScalarMappable
    from matplotlib.colors import LogNorm

    times = np.asarray(t, dtype=float)
    points = np.asarray(joint_xy)
    kappa = np.asarray(kappa)
    norm = LogNorm(vmin=kappa.min(), vmax=kappa.max())
    cmap = matplotlib.colormaps["viridis"]
    if fig is None:
        import matplotlib.pyplot as plt

        fig = plt.figure(figsize=(5, 5), layout="constrained")
    ax = fig.subplots()
    reach = np.abs(points).max() * 1.05
    ax.set(xlim=(-reach, reach), ylim=(-reach, reach * 0.3), aspect="equal")
    ax.set(xlabel="x [m]", ylabel="y [m]")
    fig.suptitle(title)  # the figure's title; the changing text sits between it and the axes
    (line,) = ax.plot([], [], "o-", lw=3, ms=3)
    label = ax.text(0.5, 1.02, "", transform=ax.transAxes, ha="center", va="bottom")
    fig.colorbar(ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="κ₂ [-]", shrink=0.6)

    def draw(k):
        line.set_data(points[k, :, 0], points[k, :, 1])
        line.set_color(cmap(norm(kappa[k])))
        label.set_text(f"t = {times[k]:.2f} s   κ₂ = {kappa[k]:.3g}")
        return line, label

    # no blitting: the text is outside the axes, which a blit would not redraw
    return FuncAnimation(fig, draw, frames=len(points), blit=False)
