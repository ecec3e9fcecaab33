"""What a run computed: the `Trajectory` record and the run statuses."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from gimwatch.errors import SimulationError
from gimwatch.watch.watch import Alarm

if TYPE_CHECKING:
    import pandas as pd

    from gimwatch.simulation.scene import Scene

__all__ = ["STATUSES", "Trajectory"]

#: How a run ended: ``stopped`` when a progress callback asked for it (a budget, a cap).
STATUSES = ("completed", "interrupted", "stopped", "stopped-on-alarm", "diverged", "failed")


@dataclass(frozen=True, eq=False)
class Trajectory:
    """What a run computed, up to where it stopped.

    Attributes:
        scene: The scene that was run.
        robot: Robot name.
        dof_names: Names of the velocity coordinates.
        t: Sample times (s), shape (K,).
        q: Configurations at the samples, shape (K, nq).
        v: Velocities at the samples, shape (K, nv).
        energy: Total energy (J) at the samples when the scene is conservative, else None.
        watch: Watch series (``watch_t`` and ``watch_<metric>``), possibly empty.
        alpha: α of the scaled diagonal ratio when watched.
        alarms: Alarms raised, in time order.
        actions: What ``on_alarm`` did (tolerances tightened, backend switched), in time order.
        backend: The dynamics backend the run ended on (the scene's, unless the robot was too
            large for Pinocchio's Data or ``switch-backend`` acted).
        status: One of `STATUSES`.
        message: Why the run stopped early ("" when completed).
        steps: Integrator steps taken.
        rhs_evaluations: Right-hand-side (forward-dynamics) evaluations.
        wall_time_s: Wall time of the integration loop.
    """

    scene: Scene
    robot: str
    dof_names: tuple[str, ...]
    t: np.ndarray
    q: np.ndarray
    v: np.ndarray
    energy: np.ndarray | None
    watch: dict[str, np.ndarray]
    alpha: float | None
    alarms: tuple[Alarm, ...]
    status: str
    message: str
    steps: int
    rhs_evaluations: int
    wall_time_s: float
    effects: tuple[str, ...] = field(default=())
    kinetic_peak: float = 0.0
    actions: tuple[str, ...] = field(default=())
    backend: str = ""

    def __repr__(self) -> str:
        """One line: the robot, how the run ended, its samples and what was watched."""
        span = f"t = 0..{self.t[-1]:.4g} s" if self.t.size else "no sample"
        watched = [k.removeprefix("watch_") for k in self.watch if k != "watch_t"]
        return (
            f"Trajectory(robot={self.robot!r}, status={self.status!r}, {span}, "
            f"{self.t.size} samples, {self.steps} steps, watched={watched}, "
            f"alarms={len(self.alarms)})"
        )

    @property
    def conservative(self) -> bool:
        """Whether the energy is a conserved quantity of this scene."""
        return self.energy is not None

    def energy_drift(self) -> float | None:
        """Relative energy drift max_t |E(t) - E(0)| / max(|E(0)|, max_t KE(t)).

        The chains start at rest where E(0) = 0 (potential zero at the horizontal), so the
        scale is the larger of |E(0)| and the peak kinetic energy (J): the energy the
        effects exchanged. None when the scene is not conservative.
        """
        if self.energy is None or self.energy.size == 0:
            return None
        deviation = float(np.max(np.abs(self.energy - self.energy[0])))
        return deviation / max(abs(float(self.energy[0])), self.kinetic_peak, 1e-300)

    def to_dataframe(self) -> pd.DataFrame:
        """The run as a table: one row per sample.

        Columns as in a results folder's ``trajectory.csv`` (``t``, ``q:<name>``,
        ``v:<name>``), then ``energy`` (conservative scenes) and the watched metrics by name
        (vectors as ``<metric>:<k>``) when sampled with the state.
        Needs pandas (``pip install 'gimwatch[pandas]'``).
        """
        from gimwatch.output.dataframe import trajectory_frame

        nq = self.q.shape[1] if self.q.ndim == 2 else 0
        names = list(self.dof_names)
        q_names = names if nq == len(names) else [f"q{i}" for i in range(nq)]
        return trajectory_frame(
            self.t,
            self.q,
            self.v,
            q_names=q_names,
            v_names=list(self.dof_names),
            energy=self.energy,
            watch=self.watch,
        )

    def raise_for_status(self) -> None:
        """Raise `SimulationError` if the run diverged or the solver failed."""
        if self.status in ("diverged", "failed"):
            raise SimulationError(float(self.t[-1]) if self.t.size else 0.0, self.message)
