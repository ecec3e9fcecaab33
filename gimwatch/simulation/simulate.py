"""Simulate a scene: declared effects + a dynamics backend + an integrator, watched at samples.

[`Simulation`][gimwatch.simulation.simulate.Simulation] owns the right-hand side and the sampling
loop only; what it composes lives in its own module, each a registry the scene schema reads:

* the robot and the initial state — `gimwatch.simulation.scene_robot`;
* effects and torque laws — [`effects`][gimwatch.simulation.effects],
  [`torque_laws`][gimwatch.simulation.torque_laws] (or a Python callable ``torque_law``);
* forward dynamics — [`backends`][gimwatch.simulation.backends];
* integrators — [`integrators`][gimwatch.simulation.integrators] (on the configuration manifold,
  [`local_coordinates`][gimwatch.simulation.local_coordinates]);
* what an alarm does — [`alarm_actions`][gimwatch.simulation.alarm_actions].

One right-hand-side evaluation is ``a = FD(q, v, Σ τ_e(t, q, v))``: the sum runs over the
*declared* torque effects only (none declared: a constant zero vector), and FD is one call
into the backend (Pinocchio's C++ recursions for ``aba`` and ``crba-cholesky``), so there is
no Python loop over joints. The watch and the energy are evaluated at the sample times
only, never inside the right-hand side.

A run ends with a status of `STATUSES`, never by an
exception: ``record`` (an alarm action) and the ``progress`` callback stop it by returning
a value; a non-finite acceleration, state or a collapsing step is ``diverged`` with the
time and the cause, the samples up to that point kept; Ctrl-C is ``interrupted``.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from gimwatch.model.robots import Robot
from gimwatch.simulation.alarm_actions import (
    ALARM_ACTIONS,
    MOST_ACCURATE_BACKEND,
    RTOL_FLOOR,
)
from gimwatch.simulation.backends import make_backend
from gimwatch.simulation.effects import CallableTorque, Gravity, build_effects
from gimwatch.simulation.integrators import INTEGRATORS, MIN_STEP_FRACTION
from gimwatch.simulation.local_coordinates import LocalChart
from gimwatch.simulation.scene import Scene
from gimwatch.simulation.scene_robot import initial_state, load_scene_robot
from gimwatch.simulation.trajectory import STATUSES, Trajectory
from gimwatch.watch.watch import Watch

__all__ = [
    "MIN_STEP_FRACTION",
    "MOST_ACCURATE_BACKEND",
    "RTOL_FLOOR",
    "STATUSES",
    "Simulation",
    "load_scene_robot",
    "run_scene",
]

TorqueLawFunction = Callable[[float, np.ndarray, np.ndarray], np.ndarray]


class _Diverged(Exception):
    """Raised inside the right-hand side: the dynamics returned non-finite values."""

    def __init__(self, time_s: float, cause: str) -> None:
        super().__init__(cause)
        self.time_s, self.cause = time_s, cause


class Simulation:
    """A scene made ready to run: robot, declared effects, backend, integrator, watch.

    Building it validates everything that needs the robot (joint and link names, lengths,
    unit (cos, sin) pairs and quaternions); nothing is integrated until
    [`run`][gimwatch.simulation.simulate.Simulation.run].

    Args:
        scene: The validated scene.
        robot: The scene's robot when already loaded.
        torque_law: A Python torque law ``tau(t, q, v)`` added to the declared effects; its
            result must be real, finite and of shape (nv,) (else
            [`TorqueLawError`][gimwatch.simulation.torque_laws.TorqueLawError] naming the law).
    """

    def __init__(
        self,
        scene: Scene,
        *,
        robot: Robot | None = None,
        torque_law: TorqueLawFunction | None = None,
    ) -> None:
        self.scene = scene
        robot = self.robot = load_scene_robot(scene) if robot is None else robot
        self.effects = build_effects(robot, scene.effects, source=scene.source)
        if torque_law is not None:
            self.effects.append(CallableTorque(robot, torque_law))
        # the gravity effect's vector (m/s²), read by the backends that apply gravity themselves
        gravity = next((e.vector for e in self.effects if isinstance(e, Gravity)), None)
        self.gravity = gravity
        self.torque_effects = [e for e in self.effects if e.adds_torque]
        self.backend = make_backend(scene.backend, robot, gravity)
        self._zero_tau = np.zeros(robot.nv)
        self._zero_tau.setflags(write=False)
        self.q0, self.v0 = initial_state(scene, robot)
        self.chart = LocalChart(robot.model)
        self.duration_s, self.sample_s = scene.duration_s, scene.sample_s
        self.integrator = INTEGRATORS[scene.integrator.method](scene.integrator)
        self.conservative = all(e.conservative for e in self.effects)
        spec = scene.watch
        self.watch = Watch(
            robot,
            spec.metrics,
            alarm_metric=spec.alarm_metric,
            alarm_threshold=spec.alarm_threshold,
            source=self.backend,
            warn=False,  # the scene's alarm action reports the alarm
        )
        self.rhs_evaluations = 0
        self.actions: list[str] = []
        self.action = ALARM_ACTIONS[spec.on_alarm](self)

    # -- dynamics ------------------------------------------------------------------------
    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Σ τ_e over the declared torque effects (N·m or N), length nv."""
        if not self.torque_effects:
            return self._zero_tau
        total = self.torque_effects[0].tau(t, q, v)
        for effect in self.torque_effects[1:]:
            total = total + effect.tau(t, q, v)
        return total

    def acceleration(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """A = FD(q, v, τ(t, q, v)) from the backend; counts one RHS evaluation."""
        self.rhs_evaluations += 1
        a = self.backend.forward_dynamics(q, v, self.tau(t, q, v))
        if not np.all(np.isfinite(a)):
            raise _Diverged(t, f"non-finite acceleration from the {self.backend.name} backend")
        return a

    def energy(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """(total, kinetic) energy in J: kinetic + gravity potential + springs, from the backend."""
        kinetic, potential = self.backend.energy(q, v)
        springs = sum(e.potential_energy(q) for e in self.effects)
        return float(kinetic + potential + springs), float(kinetic)

    # -- running -------------------------------------------------------------------------
    def run(self, *, progress: Callable[[float], object] | None = None) -> Trajectory:
        """Integrate from t = 0 to the scene's duration; stop early on divergence or alarm.

        Args:
            progress: Called with the fraction done (0..1) after each integrator step; when
                it returns a message (a non-empty string), the run stops there with status
                ``stopped`` and that message.

        Returns:
            The [`Trajectory`][gimwatch.simulation.trajectory.Trajectory] up to where the run
            stopped (Ctrl-C included).
        """
        scene = self.scene
        ts, qs, vs, energies, kinetic = [], [], [], [], [0.0]
        self.rhs_evaluations = 0
        self.actions = []
        self.integrator = INTEGRATORS[scene.integrator.method](scene.integrator)

        def record(t, q, v):
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                return "diverged", f"non-finite state at t = {t:.6g} s"
            ts.append(t)
            qs.append(np.array(q))
            vs.append(np.array(v))
            if self.conservative:
                total, kinetic_now = self.energy(q, v)
                energies.append(total)
                kinetic.append(kinetic_now)
            return self.action.after_sample(t, self.watch.sample(t, q))

        start = time.perf_counter()
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # divergence is checked per step
                outcome = record(0.0, self.q0, self.v0) or self.integrator.run(
                    self, record, progress
                )
        except KeyboardInterrupt:
            outcome = ("interrupted", "interrupted by the user (Ctrl-C)")
        except _Diverged as exc:
            outcome = ("diverged", f"{exc.cause} at t = {exc.time_s:.6g} s")
        wall = time.perf_counter() - start
        status, message = outcome
        watch = self.watch.arrays() if self.watch.metrics else {}
        if watch:  # an interrupted sample may have left the series one longer than t
            k = min(len(ts), *(len(v) for v in watch.values()))
            watch = {key: value[:k] for key, value in watch.items()}
        return Trajectory(
            scene=scene,
            robot=self.robot.name,
            dof_names=self.robot.dof_names,
            t=np.asarray(ts, dtype=float),
            q=np.asarray(qs, dtype=float).reshape(len(ts), self.robot.nq),
            v=np.asarray(vs, dtype=float).reshape(len(ts), self.robot.nv),
            energy=np.asarray(energies[: len(ts)], dtype=float) if self.conservative else None,
            watch=watch,
            alpha=self.watch.alpha,
            alarms=tuple(self.watch.alarms),
            status=status,
            message=message,
            steps=self.integrator.steps,
            rhs_evaluations=self.rhs_evaluations,
            wall_time_s=wall,
            effects=tuple(e.name for e in self.effects),
            kinetic_peak=float(max(kinetic)),
            actions=tuple(self.actions),
            backend=self.backend.name,
        )


def run_scene(
    scene: Scene,
    *,
    progress: Callable[[float], object] | None = None,
    torque_law: TorqueLawFunction | None = None,
) -> Trajectory:
    """Build and run a scene (see `Simulation`), optionally under a Python torque law.

    Examples:
        >>> import numpy as np
        >>> from gimwatch import parse_scene, run_scene
        >>> scene = parse_scene({"robot": "chain:2", "duration": 0.1, "sample": 0.05})
        >>> run = run_scene(scene, torque_law=lambda t, q, v: -0.5 * v)
        >>> run.status
        'completed'
    """
    return Simulation(scene, torque_law=torque_law).run(progress=progress)
