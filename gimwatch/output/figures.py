"""Matplotlib figures of a watched run, in the spirit of Shah & Saha (2013), Figs. 2–5.

Every function draws on ``ax`` (a new figure's axes when None), returns the Axes and
never calls ``show()``. Import matplotlib with a non-interactive backend (Agg) in scripts.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

__all__ = [
    "animate_chain",
    "plot_diagonal",
    "plot_eigenvalues",
    "plot_energy",
    "plot_joint_angles",
    "plot_kappa_and_delta",
    "plot_kappa_and_scaled",
    "plot_pivot_ratios",
]


def _axes(ax):
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=(6.4, 4.0), layout="constrained")
    return ax


def plot_eigenvalues(t: npt.ArrayLike, eigenvalues: npt.ArrayLike, *, ax=None):
    """λ_i(M) over time (Fig. 2a), largest first in the legend, log scale."""
    ax = _axes(ax)
    values = np.asarray(eigenvalues)
    for i in range(values.shape[1] - 1, -1, -1):
        ax.semilogy(t, values[:, i], label=f"λ{values.shape[1] - i}")
    ax.set(xlabel="time (s)", ylabel="eigenvalue of M (kg·m²)", title="Eigenvalues of the GIM")
    if values.shape[1] <= 10:
        ax.legend(fontsize="small", ncols=2)
    return ax


def plot_diagonal(t: npt.ArrayLike, diagonal: npt.ArrayLike, *, ax=None):
    """M_ii over time (Fig. 2b), log scale."""
    ax = _axes(ax)
    values = np.asarray(diagonal)
    for i in range(values.shape[1]):
        ax.semilogy(t, values[:, i], label=f"M{i + 1}{i + 1}")
    ax.set(xlabel="time (s)", ylabel="diagonal of M (kg·m²)", title="Diagonal elements")
    if values.shape[1] <= 10:
        ax.legend(fontsize="small", ncols=2)
    return ax


def plot_kappa_and_delta(
    t: npt.ArrayLike, kappa: npt.ArrayLike, delta: npt.ArrayLike, *, label: str = "", ax=None
):
    """κ₂ and the diagonal ratio δ over time (Figs. 2c–d and 3), log scale."""
    ax = _axes(ax)
    prefix = f"{label}: " if label else ""
    ax.semilogy(t, kappa, label=f"{prefix}κ₂")
    ax.semilogy(t, delta, "--", label=f"{prefix}δ")
    ax.set(xlabel="time (s)", ylabel="ratio", title="Condition number and diagonal ratio")
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
    ax.set(xlabel="time (s)", ylabel="ratio", title="Pivot ratios")
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
    ax.set(xlabel="time (s)", ylabel="ratio", title="Condition number and scaled diagonal ratio")
    ax.legend(fontsize="small")
    return ax


def plot_energy(t: npt.ArrayLike, energy: npt.ArrayLike, *, ax=None):
    """E(t) - E(0) (J), the energy drift of a conservative run."""
    ax = _axes(ax)
    energy = np.asarray(energy)
    ax.plot(t, energy - energy[0])
    ax.set(xlabel="time (s)", ylabel="E(t) − E(0) (J)", title="Energy drift")
    return ax


def plot_joint_angles(t: npt.ArrayLike, q: npt.ArrayLike, *, names=None, ax=None):
    """Joint coordinates over time."""
    ax = _axes(ax)
    q = np.asarray(q)
    for i in range(q.shape[1]):
        ax.plot(t, q[:, i], label=names[i] if names is not None else f"q{i + 1}")
    ax.set(xlabel="time (s)", ylabel="q", title="Joint coordinates")
    if q.shape[1] <= 10:
        ax.legend(fontsize="small", ncols=2)
    return ax


def animate_chain(
    t: npt.ArrayLike, joint_xy: npt.ArrayLike, kappa: npt.ArrayLike, *, title: str = ""
):
    """A planar chain swinging, coloured by κ₂ on a log scale; returns a FuncAnimation.

    Args:
        t: Frame times (s), shape (K,).
        joint_xy: Joint and tip positions in the plane of motion, shape (K, n + 1, 2).
        kappa: κ₂ at each frame, shape (K,).
        title: Figure title.
    """
    import matplotlib.pyplot as plt
    from matplotlib.animation import FuncAnimation
    from matplotlib.colors import LogNorm

    points = np.asarray(joint_xy)
    kappa = np.asarray(kappa)
    norm = LogNorm(vmin=kappa.min(), vmax=kappa.max())
    cmap = plt.get_cmap("viridis")
    fig, ax = plt.subplots(figsize=(5, 5), layout="constrained")
    reach = np.abs(points).max() * 1.05
    ax.set(xlim=(-reach, reach), ylim=(-reach, reach * 0.3), aspect="equal")
    ax.set(xlabel="x (m)", ylabel="y (m)", title=title)
    (line,) = ax.plot([], [], "o-", lw=3, ms=3)
    label = ax.text(0.02, 0.95, "", transform=ax.transAxes)
    fig.colorbar(plt.cm.ScalarMappable(norm=norm, cmap=cmap), ax=ax, label="κ₂", shrink=0.6)

    def draw(k):
        line.set_data(points[k, :, 0], points[k, :, 1])
        line.set_color(cmap(norm(kappa[k])))
        label.set_text(f"t = {t[k]:.2f} s   κ₂ = {kappa[k]:.3g}")
        return line, label

    return FuncAnimation(fig, draw, frames=len(points), blit=True)
