"""The results folder of a simulation: arrays, CSV, ``summary.json`` and PNG plots.

Layout of ``DIR``::

    trajectory.npz   t, q, v, energy (if conservative), watch_t, watch_<metric>
    trajectory.csv   t, q..., v...
    watch.csv        t and one column per scalar metric (when something is watched)
    summary.json     scene echo, versions, wall time, steps, RHS evaluations, status,
                     energy drift (conservative scenes), estimator quality, alarms
    *.png            joint coordinates, watched metrics, energy drift

plus the marker ``.gimwatch-results.json``. The folder is built beside ``DIR`` and swapped
into place (`gimwatch.output.folders`), so a failed or interrupted write never leaves a
half-written folder, an existing good result is replaced only by a complete one, and a folder
of other files is never replaced.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np

from gimwatch.metrics.estimator_quality import estimator_quality
from gimwatch.output.atomic import write_json_atomic, write_npz_atomic, write_text_atomic
from gimwatch.output.environment import versions
from gimwatch.output.folders import ResultsFolder
from gimwatch.simulation.simulate import Trajectory

__all__ = ["summarize", "versions", "write_simulation", "write_simulation_files"]


def summarize(trajectory: Trajectory) -> dict[str, Any]:
    """The JSON-ready summary of a run (see the module docstring)."""
    scene = trajectory.scene
    watch = trajectory.watch
    quality: Any = "needs kappa and diagonal_ratio (or scaled_diagonal_ratio) watched"
    if "watch_kappa" in watch:
        delta = watch.get("watch_diagonal_ratio")
        if delta is None and "watch_scaled_diagonal_ratio" in watch:
            # δ = αδ / α, so that estimator_quality's α is the watch's α (summary "alpha")
            delta = watch["watch_scaled_diagonal_ratio"] / (trajectory.alpha or 1.0)
        if delta is not None:
            result = estimator_quality(watch["watch_kappa"], delta)
            quality = asdict(result) if result else "fewer than 2 samples"
    maxima = {
        key.removeprefix("watch_"): float(np.max(value))
        for key, value in watch.items()
        if key != "watch_t" and value.ndim == 1 and value.size and value.dtype.kind == "f"
    }
    fallbacks = None  # how many κ-tracker samples were warm, cold restarts, dense solves
    if "watch_kappa_tracked_fallback" in watch:
        labels, counts = np.unique(watch["watch_kappa_tracked_fallback"], return_counts=True)
        fallbacks = {
            (str(label) or "warm"): int(n) for label, n in zip(labels, counts, strict=True)
        }
    return {
        "scene": {"source": scene.source, **scene.raw},
        "robot": trajectory.robot,
        "effects": list(trajectory.effects),
        "backend": trajectory.backend or scene.backend,
        "integrator": asdict(scene.integrator),
        "versions": versions(),
        "status": trajectory.status,
        "message": trajectory.message,
        "simulated_time_s": float(trajectory.t[-1]) if trajectory.t.size else 0.0,
        "samples": int(trajectory.t.size),
        "steps": trajectory.steps,
        "rhs_evaluations": trajectory.rhs_evaluations,
        "wall_time_s": trajectory.wall_time_s,
        "conservative": trajectory.conservative,
        "energy_drift_relative": trajectory.energy_drift(),
        "watched": list(scene.watch.metrics),
        "watch_maxima": maxima,
        # α = κ(t0)/δ(t0): the watch's when it watched αδ, else the estimator quality's
        "alpha": (
            trajectory.alpha
            if trajectory.alpha is not None
            else quality.get("alpha")
            if isinstance(quality, dict)
            else None
        ),
        "kappa_tracked_fallbacks": fallbacks,
        "estimator_quality": quality,
        "alarms": [asdict(alarm) for alarm in trajectory.alarms],
        "actions": list(trajectory.actions),
    }


def _csv(header: list[str], columns: list[np.ndarray]) -> str:
    """Numbers as repr(float) (round-trip exact); text columns (a fallback label) as they are."""
    lines = [",".join(header)]
    rows = zip(*columns, strict=True)
    lines += [",".join(x if isinstance(x, str) else repr(float(x)) for x in row) for row in rows]
    return "\n".join(lines) + "\n"


def _coordinate_names_and_units(trajectory: Trajectory) -> tuple[list[str], list[str] | None]:
    """Each q column's joint name and unit (rad, m, -), from the scene's robot model."""
    from gimwatch.output.figures import joint_coordinate_units
    from gimwatch.simulation.scene_robot import load_scene_robot

    try:
        names, units = joint_coordinate_units(load_scene_robot(trajectory.scene).model)
    except Exception:  # a plot label is not worth failing the results folder for
        names, units = [], []
    if len(names) != trajectory.q.shape[1]:
        return [f"q{i + 1}" for i in range(trajectory.q.shape[1])], None
    return names, units


def _plots(trajectory: Trajectory, folder: Path) -> None:
    from matplotlib.figure import Figure  # no pyplot: leaves the user's backend alone

    from gimwatch.output import figures as plots

    title = trajectory.robot

    def save(name, draw):  # each figure names its robot: figures travel without their folder
        fig = Figure(figsize=(6.4, 4.0), layout="constrained")
        draw(fig.subplots())
        fig.suptitle(title, fontsize="medium")
        fig.savefig(folder / name, dpi=110)

    t = trajectory.t
    names, units = _coordinate_names_and_units(trajectory)
    save(
        "joints.png",
        lambda ax: plots.plot_joint_angles(t, trajectory.q, names=names, units=units, ax=ax),
    )
    if trajectory.energy is not None and trajectory.energy.size:
        save("energy.png", lambda ax: plots.plot_energy(t, trajectory.energy, ax=ax))
    wt = trajectory.watch.get("watch_t")
    if wt is not None and wt.size:
        _watch_plots(trajectory, save)


def _watch_plots(trajectory: Trajectory, save: Callable) -> None:
    """The watch's figures, each drawn when the series it plots were watched."""
    from gimwatch.output import figures as plots

    watch = trajectory.watch
    wt = watch["watch_t"]
    if "watch_kappa" in watch and "watch_diagonal_ratio" in watch:
        save(
            "kappa_delta.png",
            lambda ax: plots.plot_kappa_and_delta(
                wt, watch["watch_kappa"], watch["watch_diagonal_ratio"], ax=ax
            ),
        )
    if "watch_diagonal_ratio" in watch:
        spec = trajectory.scene.watch
        threshold = spec.alarm_threshold if spec.alarm_metric == "diagonal_ratio" else None
        save(
            "delta.png",
            lambda ax: plots.plot_delta(
                wt, watch["watch_diagonal_ratio"], threshold=threshold, ax=ax
            ),
        )
    if "watch_kappa" in watch and "watch_scaled_diagonal_ratio" in watch:
        save(
            "kappa_scaled.png",
            lambda ax: plots.plot_kappa_and_scaled(
                wt, watch["watch_kappa"], watch["watch_scaled_diagonal_ratio"], ax=ax
            ),
        )
    if "watch_pivot_ratio_forward" in watch:
        save(
            "pivot_ratios.png",
            lambda ax: plots.plot_pivot_ratios(
                wt,
                watch["watch_pivot_ratio_forward"],
                watch.get("watch_pivot_ratio_backward"),
                watch.get("watch_kappa"),
                ax=ax,
            ),
        )
    if "watch_eigenvalues" in watch:
        save(
            "eigenvalues.png",
            lambda ax: plots.plot_eigenvalues(wt, watch["watch_eigenvalues"], ax=ax),
        )
    if "watch_diagonal" in watch:
        diagonal = watch["watch_diagonal"]
        names = trajectory.dof_names if len(trajectory.dof_names) == diagonal.shape[1] else None
        save("diagonal.png", lambda ax: plots.plot_diagonal(wt, diagonal, names=names, ax=ax))


def write_simulation_files(trajectory: Trajectory, folder: Path, *, plots: bool = True) -> None:
    """Write the files of the results folder of ``trajectory`` into the existing ``folder``."""
    arrays = {"t": trajectory.t, "q": trajectory.q, "v": trajectory.v, **trajectory.watch}
    if trajectory.energy is not None:
        arrays["energy"] = trajectory.energy
    write_npz_atomic(folder / "trajectory.npz", arrays)
    names = list(trajectory.dof_names)
    nq = trajectory.q.shape[1]
    q_names = names if nq == len(names) else [f"q{i}" for i in range(nq)]
    header = ["t", *(f"q:{n}" for n in q_names), *(f"v:{n}" for n in names)]
    write_text_atomic(
        folder / "trajectory.csv",
        _csv(header, [trajectory.t, *trajectory.q.T, *trajectory.v.T]),
    )
    scalar = {k: v for k, v in trajectory.watch.items() if k != "watch_t" and v.ndim == 1}
    if scalar:
        write_text_atomic(
            folder / "watch.csv",
            _csv(
                ["t", *(k.removeprefix("watch_") for k in scalar)],
                [trajectory.watch["watch_t"], *scalar.values()],
            ),
        )
    write_json_atomic(folder / "summary.json", summarize(trajectory))
    if plots and trajectory.t.size:
        _plots(trajectory, folder)


def write_simulation(trajectory: Trajectory, directory: str | Path, *, plots: bool = True) -> Path:
    """Write the results folder of ``trajectory`` to ``directory`` (replaced atomically).

    Raises:
        OutputError: ``directory`` is not a gimwatch results folder and not empty, is not a
            folder, is being written by another process, or cannot be written; the previous
            folder is then left as it was.
    """
    with ResultsFolder(directory, writer="simulate") as folder:
        assert folder.staging is not None  # set on entering the folder
        write_simulation_files(trajectory, folder.staging, plots=plots)
        return folder.commit()
