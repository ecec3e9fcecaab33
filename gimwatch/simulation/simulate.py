"""Simulate a scene: declared effects + a dynamics backend + an integrator, watched at samples.

The state is x = (q, v). One right-hand-side evaluation is
``ẋ = (v, FD(q, v, Σ τ_e(t, q, v)))``: the sum runs over the *declared* torque effects only
(none declared: a constant zero vector), and FD is one call into the backend (Pinocchio's
C++ recursions for ``aba`` and ``crba-cholesky``), so there is no Python loop over joints.

Integrators: SciPy's ``RK45``, ``DOP853``, ``Radau`` and ``LSODA`` (adaptive, ``rtol``/
``atol``), driven step by step so that samples come from the solver's dense output, a
progress callback runs between steps and Ctrl-C keeps what was computed; and fixed-step
``RK4`` and semi-implicit (symplectic) Euler with step ``dt``. The watch and the energy are
evaluated at the sample times only, never inside the right-hand side.

When the watch's alarm metric is above its threshold, ``watch.on_alarm`` acts (issue 6):
``warn`` records the alarm, ``stop`` ends the run cleanly, ``tighten`` lowers the adaptive
integrator's tolerances in proportion to the estimate,
``rtol ← max(rtol₀ · threshold / estimate, RTOL_FLOOR)`` (atol by the same factor), at each
sample where the metric is above the threshold and the estimate is a new maximum (never
loosened again), and
``switch-backend`` moves the dynamics to :data:`MOST_ACCURATE_BACKEND`.

Divergence: a non-finite state or acceleration, or a step size that collapses below
``MIN_STEP_FRACTION · duration``, stops the run with status ``diverged`` and a message giving
the time and the cause; the samples up to that point are kept.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
import scipy.integrate

from gimwatch.errors import GimwatchError, SceneError, SimulationError
from gimwatch.metrics.watch import Alarm, Watch
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import (
    DATA_NV_LIMIT,
    Robot,
    _too_large,
    chain_robot,
    load_robot,
    neutral_configuration,
)
from gimwatch.simulation.backends import make_backend
from gimwatch.simulation.effects import build_effects, joint_vector
from gimwatch.simulation.scene import Scene

__all__ = [
    "MIN_STEP_FRACTION",
    "MOST_ACCURATE_BACKEND",
    "RTOL_FLOOR",
    "STATUSES",
    "Simulation",
    "Trajectory",
    "load_scene_robot",
    "run_scene",
]

STATUSES = ("completed", "interrupted", "stopped-on-alarm", "diverged", "failed")
_SCIPY = {
    "RK45": scipy.integrate.RK45,
    "DOP853": scipy.integrate.DOP853,
    "Radau": scipy.integrate.Radau,
    "LSODA": scipy.integrate.LSODA,
}
#: The backend with the smallest q̈ error on the stress suite's hard cases (ABA stays within
#: ~1e-14 of the mpmath reference up to κ ~ 1e11 while CRBA + Cholesky scales with κ·eps);
#: ``on_alarm = "switch-backend"`` moves to it.
MOST_ACCURATE_BACKEND = "aba"
#: ``tighten`` never asks for a relative tolerance below this (SciPy clamps at 100·eps).
RTOL_FLOOR = 1e-13
#: Methods whose tolerances can change between steps (LSODA keeps them in Fortran state).
_TIGHTENABLE = ("RK45", "DOP853", "Radau")
#: A step shorter than this fraction of the duration is a collapse (the run diverges).
MIN_STEP_FRACTION = 1e-12

if TYPE_CHECKING:
    import pandas as pd


class _Diverged(Exception):
    """Raised inside the right-hand side: the dynamics returned non-finite values."""

    def __init__(self, time_s: float, cause: str) -> None:
        super().__init__(cause)
        self.time_s, self.cause = time_s, cause


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
        status: One of :data:`STATUSES`.
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
        """Raise :class:`SimulationError` if the run diverged or the solver failed."""
        if self.status in ("diverged", "failed"):
            raise SimulationError(float(self.t[-1]) if self.t.size else 0.0, self.message)


def _chain_robot(params: dict, floating: bool) -> Robot:
    # checked before any URDF is generated: a floating base needs Pinocchio's Data (memory
    # ∝ nv³); a fixed one runs on the O(n) denoc backend, up to the URDF parser's depth
    # (chain_robot checks that)
    if floating and params["n"] + 6 > DATA_NV_LIMIT:
        raise _too_large(f"chain:{params['n']}", params["n"] + 6)
    options = {k: v for k, v in params.items() if k != "n"}
    return chain_robot(chain_spec(params["n"], **options), floating=floating)


def load_scene_robot(scene: Scene) -> Robot:
    """Load the scene's robot; failures become a :class:`SceneError` on key ``robot``."""
    try:
        if scene.robot.chain is not None:
            return _chain_robot(scene.robot.chain, scene.robot.floating)
        floating = scene.robot.floating
        return load_robot(
            scene.robot.spec, floating=floating, max_nv=DATA_NV_LIMIT if floating else None
        )
    except SceneError:
        raise
    except GimwatchError as exc:
        raise scene.error("robot", str(exc)) from exc


class Simulation:
    """A scene made ready to run: robot, declared effects, backend, integrator, watch.

    Building it validates everything that needs the robot (joint and link names, lengths);
    nothing is integrated until :meth:`run`.
    """

    def __init__(self, scene: Scene, *, robot: Robot | None = None) -> None:
        self.scene = scene
        robot = self.robot = load_scene_robot(scene) if robot is None else robot
        self.effects = build_effects(robot, scene.effects, source=scene.source)
        gravity = next((e.vector for e in self.effects if e.name == "gravity"), None)
        self.gravity = gravity
        self.torque_effects = [e for e in self.effects if e.adds_torque]
        self.backend = make_backend(scene.backend, robot, gravity)
        self._zero_tau = np.zeros(robot.nv)
        self._zero_tau.setflags(write=False)
        q0 = neutral_configuration(robot)
        self.q0 = (
            q0
            if scene.q is None
            else joint_vector(robot, scene.q, source=scene.source, key="q", space="q", default=q0)
        )
        self.v0 = joint_vector(robot, scene.v, source=scene.source, key="v")
        self.euclidean = robot.nq == robot.nv
        if not self.euclidean and not scene.integrator.fixed_step:
            raise scene.error(
                "integrator.method",
                f"{scene.integrator.method} integrates q as a vector; {robot.name} has "
                "quaternion coordinates: use RK4 or semi-implicit-euler",
            )
        self.conservative = all(e.conservative for e in self.effects)
        spec = scene.watch
        self.watch = Watch(
            robot,
            spec.metrics,
            alarm_metric=spec.alarm_metric,
            alarm_threshold=spec.alarm_threshold,
            dynamics=self.backend,
        )
        self.rhs_evaluations = 0
        self._fallback = self._check_on_alarm(gravity)

    def _check_on_alarm(self, gravity):
        """Validate ``watch.on_alarm`` against the integrator/backend; build what it needs."""
        scene, action = self.scene, self.scene.watch.on_alarm
        if action == "tighten" and scene.integrator.method not in _TIGHTENABLE:
            raise scene.error(
                "watch.on_alarm",
                f"tighten needs an adaptive integrator ({', '.join(_TIGHTENABLE)}), "
                f"got {scene.integrator.method}",
            )
        if action == "switch-backend":
            if scene.backend == MOST_ACCURATE_BACKEND:
                raise scene.error(
                    "watch.on_alarm",
                    f"switch-backend moves to {MOST_ACCURATE_BACKEND}, which the scene "
                    "already uses (dynamics.backend)",
                )
            return make_backend(MOST_ACCURATE_BACKEND, self.robot, gravity)
        return None

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

    def rhs(self, t: float, x: np.ndarray) -> np.ndarray:
        """ẋ = (v, a) for x = (q, v) (Euclidean q only)."""
        nq = self.robot.nq
        q, v = x[:nq], x[nq:]
        return np.concatenate((v, self.acceleration(t, q, v)))

    def energy(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """(total, kinetic) energy in J: kinetic + gravity potential + springs, from the backend."""
        kinetic, potential = self.backend.energy(q, v)
        springs = sum(e.potential_energy(q) for e in self.effects)
        return float(kinetic + potential + springs), float(kinetic)

    # -- running -------------------------------------------------------------------------
    def _integrate_q(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        return q + dq if self.euclidean else pin.integrate(self.robot.model, q, dq)

    def _fixed_steps(self, record, progress):
        spec = self.scene.integrator
        dt = spec.dt
        n_steps = round(self.scene.duration_s / dt)
        every = round(self.scene.sample_s / dt)
        q, v = self.q0.copy(), self.v0.copy()
        f = self.acceleration
        for k in range(n_steps):
            t = k * dt
            if spec.method == "RK4":
                a1 = f(t, q, v)
                q2, v2 = self._integrate_q(q, 0.5 * dt * v), v + 0.5 * dt * a1
                a2 = f(t + 0.5 * dt, q2, v2)
                q3, v3 = self._integrate_q(q, 0.5 * dt * v2), v + 0.5 * dt * a2
                a3 = f(t + 0.5 * dt, q3, v3)
                q4, v4 = self._integrate_q(q, dt * v3), v + dt * a3
                a4 = f(t + dt, q4, v4)
                q = self._integrate_q(q, dt / 6.0 * (v + 2 * v2 + 2 * v3 + v4))
                v = v + dt / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)
            else:  # semi-implicit Euler: v first, then q with the new v
                v = v + dt * f(t, q, v)
                q = self._integrate_q(q, dt * v)
            self.steps += 1
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                return "diverged", f"non-finite state after step {k + 1} (t = {t + dt:.6g} s)"
            if (k + 1) % every == 0:
                stop = record((k + 1) * dt, q, v)
                if stop:
                    return stop
            if progress is not None:
                progress((k + 1) / n_steps)
        return "completed", ""

    def _scipy_steps(self, record, progress, sample_times):
        spec = self.scene.integrator
        x0 = np.concatenate((self.q0, self.v0))
        solver = _SCIPY[spec.method](
            self.rhs,
            0.0,
            x0,
            self.scene.duration_s,
            rtol=spec.rtol,
            atol=spec.atol,
            max_step=spec.max_step,
        )
        self._solver = solver
        nq = self.robot.nq
        next_sample = 1
        min_step = MIN_STEP_FRACTION * self.scene.duration_s
        while solver.status == "running":
            message = solver.step()
            if solver.status == "failed":
                if "step size" in str(message):
                    return "diverged", (
                        f"step size collapsed at t = {solver.t:.6g} s ({spec.method}: {message})"
                    )
                return "failed", f"{spec.method} failed at t = {solver.t:.6g} s: {message}"
            self.steps += 1
            if not np.all(np.isfinite(solver.y)):
                return "diverged", f"non-finite state at t = {solver.t:.6g} s"
            step = solver.step_size
            if solver.status == "running" and step is not None and step < min_step:
                return "diverged", (
                    f"step size collapsed to {step:.3g} s (< {min_step:.3g} s) at "
                    f"t = {solver.t:.6g} s: the dynamics are blowing up or too stiff for "
                    f"{spec.method}"
                )
            due = next_sample
            while due < sample_times.size and sample_times[due] <= solver.t + 1e-12:
                due += 1
            if due > next_sample:
                dense = solver.dense_output()
                for ts in sample_times[next_sample:due]:
                    x = solver.y if ts == solver.t else dense(min(ts, solver.t))
                    stop = record(float(ts), x[:nq], x[nq:])
                    if stop:
                        return stop
                next_sample = due
            if progress is not None:
                progress(solver.t / self.scene.duration_s)
        return "completed", ""

    def run(self, *, progress: Callable[[float], None] | None = None) -> Trajectory:
        """Integrate from t = 0 to the scene's duration; stop early on divergence or alarm.

        Args:
            progress: Called with the fraction done (0..1) after each integrator step.

        Returns:
            The :class:`Trajectory` up to where the run stopped (Ctrl-C included).
        """
        scene = self.scene
        count = int(np.floor(scene.duration_s / scene.sample_s + 1e-9)) + 1
        sample_times = np.arange(count) * scene.sample_s
        ts, qs, vs, energies, kinetic = [], [], [], [], [0.0]
        self.steps = 0
        self.rhs_evaluations = 0
        self.actions: list[str] = []
        self._solver = None

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
            alarm = self.watch.sample(t, q)
            if alarm is not None and scene.watch.on_alarm == "stop":
                return (
                    "stopped-on-alarm",
                    f"{alarm.metric} = {alarm.value:.4g} crossed {alarm.threshold:.4g} "
                    f"at t = {t:.6g} s",
                )
            if alarm is not None and self._fallback is not None:
                self.actions.append(
                    f"t = {t:.6g} s: backend {self.backend.name} -> {self._fallback.name}"
                )
                self.backend, self._fallback = self._fallback, None
            if scene.watch.on_alarm == "tighten":
                self._tighten(t)
            return None

        start = time.perf_counter()
        try:
            with np.errstate(over="ignore", invalid="ignore"):  # divergence is checked per step
                outcome = record(0.0, self.q0, self.v0) or (
                    self._fixed_steps(record, progress)
                    if scene.integrator.fixed_step
                    else self._scipy_steps(record, progress, sample_times)
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
            steps=self.steps,
            rhs_evaluations=self.rhs_evaluations,
            wall_time_s=wall,
            effects=scene.effect_names,
            kinetic_peak=float(max(kinetic)),
            actions=tuple(self.actions),
            backend=self.backend.name,
        )

    def _tighten(self, t: float) -> None:
        """Set rtol ← max(rtol₀ · threshold / estimate, RTOL_FLOOR), atol by the same factor."""
        watch, solver = self.watch, self._solver
        if solver is None or watch.alarm_metric is None:  # the t0 sample comes before the solver
            return
        value = watch.series[watch.alarm_metric][-1]
        estimate = watch.metrics[watch.alarm_metric].severity(value)
        spec = self.scene.integrator
        if not estimate > watch.alarm_threshold:
            return
        factor = max(watch.alarm_threshold / estimate, RTOL_FLOOR / spec.rtol)
        rtol = spec.rtol * factor
        if rtol >= 0.99 * float(np.min(solver.rtol)):  # only ever tighten
            return
        self.actions.append(
            f"t = {t:.6g} s: {watch.alarm_metric} = {value:.4g}, "
            f"rtol {float(np.min(solver.rtol)):.3g} -> {rtol:.3g}"
        )
        solver.rtol, solver.atol = rtol, spec.atol * factor
        if hasattr(solver, "newton_tol"):  # Radau's Newton tolerance follows rtol
            solver.newton_tol = max(10 * np.finfo(float).eps / rtol, min(0.03, rtol**0.5))


def run_scene(scene: Scene, *, progress: Callable[[float], None] | None = None) -> Trajectory:
    """Build and run a scene (see :class:`Simulation`)."""
    return Simulation(scene).run(progress=progress)
