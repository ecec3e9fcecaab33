"""Integrators: advance (q, v) from t = 0 to the scene's duration, in a registry.

Adaptive (SciPy's ``RK45``, ``DOP853``, ``Radau``, ``LSODA``; ``rtol``/``atol``) and
fixed-step (``RK4``, ``semi-implicit-euler``; ``dt``) methods share one interface:
[`Integrator.run`][gimwatch.simulation.integrators.Integrator.run] takes the
[`Problem`][gimwatch.simulation.integrators.Problem] to solve (the simulation), a ``record``
callback for the sample times and a ``progress`` callback between steps, and returns the outcome
``(status, message)``. Either callback stops the run by *returning* a value: ``record`` a ``(status,
message)`` pair, ``progress`` a message (status ``stopped``).

Every method integrates on the configuration manifold
([`gimwatch.simulation.local_coordinates`][gimwatch.simulation.local_coordinates]): for nq = nv the
state is (q, v) itself; otherwise (continuous joints, floating base) it is (Δq, v) around an anchor.
The adaptive methods then run piecewise between sample times — a new solver per piece, re-anchored
at each sample (and within a piece when ‖Δq‖∞ exceeds `REANCHOR_NORM`) — and the
fixed-step methods re-anchor at every step.

How to add an integrator: subclass
[`FixedStepIntegrator`][gimwatch.simulation.integrators.FixedStepIntegrator] and implement
[`FixedStepIntegrator.step`][gimwatch.simulation.integrators.FixedStepIntegrator.step] (or
[`ScipyIntegrator`][gimwatch.simulation.integrators.ScipyIntegrator] and set ``solver``, any
`scipy.integrate.OdeSolver`), give it a ``name``, decorate it with
[`register`][gimwatch.simulation.integrators.register]. The scene schema, ``simulate --help`` and
the scene reference read `INTEGRATORS`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import ClassVar, Protocol

import numpy as np
import scipy.integrate

from gimwatch.registries import Registry
from gimwatch.simulation.local_coordinates import LocalChart

__all__ = [
    "INTEGRATORS",
    "MIN_STEP_FRACTION",
    "REANCHOR_NORM",
    "FixedStepIntegrator",
    "Integrator",
    "Outcome",
    "Problem",
    "ScipyIntegrator",
    "register",
]

#: The step budget of a spec without ``max_steps`` (the scene's default, scene_integrator).
DEFAULT_MAX_STEPS = 100_000
#: A step shorter than this fraction of the duration is a collapse (the run diverges).
MIN_STEP_FRACTION = 1e-12
#: Within a piece, an adaptive method re-anchors when ‖Δq‖∞ exceeds this (rad or m).
REANCHOR_NORM = 1.0

Outcome = tuple[str, str]
Record = Callable[[float, np.ndarray, np.ndarray], "Outcome | None"]
Progress = Callable[[float], object] | None


class Problem(Protocol):
    """What an integrator needs from the simulation."""

    q0: np.ndarray
    v0: np.ndarray
    chart: LocalChart
    duration_s: float
    sample_s: float

    def acceleration(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Joint accelerations (length nv) at (t, q, v)."""


def _budget_spent(steps: int, t: float, duration_s: float, method: str) -> str:
    return (
        f"step budget spent: {steps} {method} steps reached t = {t:.6g} s of {duration_s:.6g} s "
        "(the dynamics may be too stiff for this method: try Radau, or raise [integrator] "
        "max_steps)"
    )


def _stopped(progress: Progress, fraction: float) -> Outcome | None:
    """Call ``progress``; a returned message stops the run with status ``stopped``."""
    if progress is None:
        return None
    message = progress(fraction)
    return ("stopped", str(message)) if message else None


class Integrator:
    """Base class of the integrators.

    Contract:
        * ``name`` — the scene name (``[integrator] method``), unique in `INTEGRATORS`.
        * ``fixed_step`` — True: the scene gives ``dt`` (and no rtol/atol/max_step);
          False: ``rtol``, ``atol``, ``max_step``.
        * ``tightenable`` — whether ``on_alarm = "tighten"`` may lower its tolerances between
          steps ([`current_rtol`][gimwatch.simulation.integrators.Integrator.current_rtol],
          [`set_tolerances`][gimwatch.simulation.integrators.Integrator.set_tolerances]).
        * ``__init__(spec)`` takes the scene's ``IntegratorSpec``.
        * [`run`][gimwatch.simulation.integrators.Integrator.run] integrates from t = 0 to
          ``problem.duration_s``, calls ``record(t, q, v)`` at every sample time after t = 0 and
          ``progress(fraction)`` between steps, counts `steps`, and returns ``(status, message)``:
          ``("completed", "")``, what ``record`` returned, ``("stopped", message)`` when
          ``progress`` returned a message, ``("diverged", why)`` on a non-finite state or a
          collapsing step, ``("failed", why)`` (the step budget ``spec.max_steps`` spent, among
          others).
    """

    name: ClassVar[str]
    fixed_step: ClassVar[bool] = False
    tightenable: ClassVar[bool] = False

    def __init__(self, spec) -> None:
        self.spec = spec
        self.steps = 0
        #: The step budget: ``failed`` once spent (adaptive) or refused (fixed step).
        self.max_steps = int(getattr(spec, "max_steps", DEFAULT_MAX_STEPS))

    def run(self, problem: Problem, record: Record, progress: Progress = None) -> Outcome:
        """Integrate the whole run; see the class contract."""
        raise NotImplementedError

    def current_rtol(self) -> float | None:
        """The relative tolerance in force (None before the first step, or fixed-step)."""
        return None

    def set_tolerances(self, rtol: float, atol: float) -> None:
        """Change rtol and atol from the next step on (tightenable methods)."""
        raise NotImplementedError(f"{self.name} cannot change its tolerances")


#: The registry: scene method name -> class.
INTEGRATORS: Registry[type[Integrator]] = Registry("integrator")


register = INTEGRATORS.register
"""Class decorator: add an integrator to `INTEGRATORS` under its ``name``."""


# -- adaptive (SciPy) -------------------------------------------------------------------
class ScipyIntegrator(Integrator):
    """A SciPy `OdeSolver` driven step by step.

    Samples come from the solver's dense output (Euclidean q) or are the ends of the pieces
    (manifold q); ``progress`` runs between steps.
    """

    solver: ClassVar[type[scipy.integrate.OdeSolver]]

    def __init__(self, spec) -> None:
        super().__init__(spec)
        self.rtol, self.atol = spec.rtol, spec.atol
        self._solver: scipy.integrate.OdeSolver | None = None

    def current_rtol(self) -> float | None:
        """The current solver's smallest rtol (None before the first solver exists)."""
        return None if self._solver is None else float(np.min(self._solver.rtol))

    def set_tolerances(self, rtol: float, atol: float) -> None:
        """New tolerances for the current solver and every later piece."""
        self.rtol, self.atol = rtol, atol
        solver = self._solver
        if solver is None:
            return
        solver.rtol, solver.atol = rtol, atol
        if hasattr(solver, "newton_tol"):  # Radau's Newton tolerance follows rtol
            solver.newton_tol = max(10 * np.finfo(float).eps / rtol, min(0.03, rtol**0.5))

    def _start(self, fun, t0: float, y0: np.ndarray, t_bound: float):
        self._solver = self.solver(
            fun, t0, y0, t_bound, rtol=self.rtol, atol=self.atol, max_step=self.spec.max_step
        )
        return self._solver

    def _advance(self, solver, duration_s: float) -> Outcome | None:
        """One step with the failure, finiteness and step-collapse checks."""
        method = self.name
        message = solver.step()
        if solver.status == "failed":
            if "step size" in str(message):
                return "diverged", (
                    f"step size collapsed at t = {solver.t:.6g} s ({method}: {message})"
                )
            return "failed", f"{method} failed at t = {solver.t:.6g} s: {message}"
        self.steps += 1
        if not np.all(np.isfinite(solver.y)):
            return "diverged", f"non-finite state at t = {solver.t:.6g} s"
        if solver.status == "running" and self.steps >= self.max_steps:
            return "failed", _budget_spent(self.max_steps, solver.t, duration_s, method)
        step, min_step = solver.step_size, MIN_STEP_FRACTION * duration_s
        if solver.status == "running" and step is not None and step < min_step:
            return "diverged", (
                f"step size collapsed to {step:.3g} s (< {min_step:.3g} s) at "
                f"t = {solver.t:.6g} s: the dynamics are blowing up or too stiff for {method}"
            )
        return None

    def run(self, problem: Problem, record: Record, progress: Progress = None) -> Outcome:
        """Integrate in one piece (Euclidean q) or piecewise between samples (manifold q)."""
        count = int(np.floor(problem.duration_s / problem.sample_s + 1e-9)) + 1
        sample_times = np.arange(count) * problem.sample_s
        if problem.chart.euclidean:
            return self._run_vector(problem, record, progress, sample_times)
        return self._run_pieces(problem, record, progress, sample_times)

    def _run_vector(self, problem, record, progress, sample_times) -> Outcome:
        """Euclidean q: one solver for the whole run, samples from its dense output."""
        nq, duration = problem.q0.size, problem.duration_s

        def rhs(t, x):
            q, v = x[:nq], x[nq:]
            return np.concatenate((v, problem.acceleration(t, q, v)))

        solver = self._start(rhs, 0.0, np.concatenate((problem.q0, problem.v0)), duration)
        next_sample = 1
        while solver.status == "running":
            outcome = self._advance(solver, duration)
            if outcome:
                return outcome
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
            stop = _stopped(progress, solver.t / duration)
            if stop:
                return stop
        return "completed", ""

    def _run_pieces(self, problem, record, progress, sample_times) -> Outcome:
        """Manifold q: state (Δq, v) around an anchor; a new solver per piece.

        Pieces end at the sample times (and at the duration); the anchor moves to the
        piece's end configuration, or mid-piece when ‖Δq‖∞ > `REANCHOR_NORM`.
        """
        chart, duration = problem.chart, problem.duration_s
        nv = problem.v0.size
        ends = [min(float(ts), duration) for ts in sample_times[1:]]
        if not ends or ends[-1] < duration - 1e-12 * duration:
            ends.append(duration)
        t, anchor, v = 0.0, problem.q0.copy(), problem.v0.copy()
        for index, t_end in enumerate(ends):
            is_sample = index + 1 < sample_times.size
            while True:

                def rhs(t_, y, anchor=anchor):
                    dq, v_ = y[:nv], y[nv:]
                    q = chart.integrate(anchor, dq)
                    a = problem.acceleration(t_, q, v_)
                    return np.concatenate((chart.local_rate(anchor, dq, v_), a))

                solver = self._start(rhs, t, np.concatenate((np.zeros(nv), v)), t_end)
                reanchored = False
                while solver.status == "running":
                    outcome = self._advance(solver, duration)
                    if outcome:
                        return outcome
                    dq = solver.y[:nv]
                    stop = _stopped(progress, solver.t / duration)
                    if stop:
                        return stop
                    if solver.status == "running" and np.max(np.abs(dq)) > REANCHOR_NORM:
                        reanchored = True
                        break
                t, anchor = solver.t, chart.integrate(anchor, solver.y[:nv])
                v = solver.y[nv:].copy()
                if not reanchored:
                    break
            if is_sample:
                stop = record(float(sample_times[index + 1]), anchor, v)
                if stop:
                    return stop
        return "completed", ""


def _scipy(method: str) -> type[ScipyIntegrator]:
    cls = type(
        method,
        (ScipyIntegrator,),
        {
            "name": method,
            "solver": getattr(scipy.integrate, method),
            # LSODA keeps its tolerances in Fortran state: they cannot change between steps
            "tightenable": method != "LSODA",
            "__doc__": f"SciPy's ``{method}`` (adaptive; rtol, atol, max_step).",
            "__module__": __name__,
        },
    )
    register(cls)
    return cls


RK45 = _scipy("RK45")
DOP853 = _scipy("DOP853")
Radau = _scipy("Radau")
LSODA = _scipy("LSODA")


# -- fixed step -------------------------------------------------------------------------
class FixedStepIntegrator(Integrator):
    """Steps of ``spec.dt``, re-anchored at every step; samples every ``sample / dt`` steps."""

    fixed_step = True

    def step(
        self,
        f: Callable[[float, np.ndarray, np.ndarray], np.ndarray],
        chart: LocalChart,
        t: float,
        q: np.ndarray,
        v: np.ndarray,
        dt: float,
    ) -> tuple[np.ndarray, np.ndarray]:
        """One step from (t, q, v): the new (q, v), with q = chart.integrate(q, Δq)."""
        raise NotImplementedError

    def run(self, problem: Problem, record: Record, progress: Progress = None) -> Outcome:
        """Take round(duration / dt) steps; see `Integrator`."""
        dt = self.spec.dt
        n_steps = round(problem.duration_s / dt)
        if n_steps > self.max_steps:  # a scene refuses it; a spec built in Python may not
            return "failed", _budget_spent(self.max_steps, 0.0, problem.duration_s, self.name)
        every = round(problem.sample_s / dt)
        q, v = problem.q0.copy(), problem.v0.copy()
        for k in range(n_steps):
            t = k * dt
            q, v = self.step(problem.acceleration, problem.chart, t, q, v, dt)
            self.steps += 1
            if not (np.all(np.isfinite(q)) and np.all(np.isfinite(v))):
                return "diverged", f"non-finite state after step {k + 1} (t = {t + dt:.6g} s)"
            if (k + 1) % every == 0:
                stop = record((k + 1) * dt, q, v)
                if stop:
                    return stop
            stop = _stopped(progress, (k + 1) / n_steps)
            if stop:
                return stop
        return "completed", ""


@register
class RK4(FixedStepIntegrator):
    """Classical Runge-Kutta 4 in local coordinates around the step's start q.

    Stage i has Δq_i = c_i dt k_{i-1} and rate k_i = J(Δq_i)⁻¹ v_i (k_1 = v: J(0) = I);
    q ← q ⊕ dt/6 (k₁ + 2k₂ + 2k₃ + k₄), v ← v + dt/6 (a₁ + 2a₂ + 2a₃ + a₄).
    """

    name = "RK4"

    def step(self, f, chart, t, q, v, dt):
        a1 = f(t, q, v)
        d1 = v
        q2, v2 = chart.integrate(q, 0.5 * dt * d1), v + 0.5 * dt * a1
        a2 = f(t + 0.5 * dt, q2, v2)
        d2 = chart.local_rate(q, 0.5 * dt * d1, v2)
        q3, v3 = chart.integrate(q, 0.5 * dt * d2), v + 0.5 * dt * a2
        a3 = f(t + 0.5 * dt, q3, v3)
        d3 = chart.local_rate(q, 0.5 * dt * d2, v3)
        q4, v4 = chart.integrate(q, dt * d3), v + dt * a3
        a4 = f(t + dt, q4, v4)
        d4 = chart.local_rate(q, dt * d3, v4)
        q_new = chart.integrate(q, dt / 6.0 * (d1 + 2 * d2 + 2 * d3 + d4))
        return q_new, v + dt / 6.0 * (a1 + 2 * a2 + 2 * a3 + a4)


@register
class SemiImplicitEuler(FixedStepIntegrator):
    """Symplectic Euler: v ← v + dt a(q, v), then q ← q ⊕ dt v (first order)."""

    name = "semi-implicit-euler"

    def step(self, f, chart, t, q, v, dt):
        v = v + dt * f(t, q, v)
        return chart.integrate(q, dt * v), v
