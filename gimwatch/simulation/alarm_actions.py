"""What a run does when the watch's alarm metric crosses its threshold (``watch.on_alarm``).

* ``warn`` — record the alarm (the CLI prints it); the run goes on.
* ``stop`` — end the run cleanly (status ``stopped-on-alarm``), samples kept.
* ``tighten`` — lower the adaptive integrator's tolerances in proportion to the estimate,
  ``rtol ← max(rtol₀ · threshold / estimate, RTOL_FLOOR)`` (atol by the same factor), at
  each sample where the metric is above the threshold and the estimate is a new maximum
  (never loosened again).
* ``switch-backend`` — move the dynamics to `MOST_ACCURATE_BACKEND` at the first alarm.

How to add an action: subclass [`AlarmAction`][gimwatch.simulation.alarm_actions.AlarmAction], set
``name``, check in ``__init__`` that it can apply to the simulation (else raise its scene's error on
``watch.on_alarm``), implement
[`AlarmAction.after_sample`][gimwatch.simulation.alarm_actions.AlarmAction.after_sample], decorate
with [`register`][gimwatch.simulation.alarm_actions.register]. The scene schema, the CLI and the
scene reference read `ALARM_ACTIONS`.
"""

from __future__ import annotations

from typing import Any, ClassVar, Protocol

from gimwatch.registries import Registry
from gimwatch.simulation.backends import make_backend
from gimwatch.simulation.integrators import INTEGRATORS
from gimwatch.watch.watch import Alarm

__all__ = [
    "ALARM_ACTIONS",
    "MOST_ACCURATE_BACKEND",
    "RTOL_FLOOR",
    "AlarmAction",
    "register",
]

#: The backend with the smallest q̈ error on the stress suite's hard cases (ABA stays within
#: ~1e-14 of the mpmath reference up to κ ~ 1e11 while CRBA + Cholesky scales with κ·eps);
#: ``on_alarm = "switch-backend"`` moves to it.
MOST_ACCURATE_BACKEND = "aba"
#: ``tighten`` never asks for a relative tolerance below this (SciPy clamps at 100·eps).
RTOL_FLOOR = 1e-13


class Simulation(Protocol):
    """What an action reads and changes of a `gimwatch.simulation.simulate.Simulation`.

    A protocol rather than an import: ``simulate`` imports this module's registry.
    """

    scene: Any
    robot: Any
    gravity: Any
    watch: Any
    integrator: Any
    backend: Any
    actions: list[str]


class AlarmAction:
    """Base class of the on-alarm actions.

    Contract:
        * ``name`` — the scene name (``watch.on_alarm``), unique in `ALARM_ACTIONS`.
        * ``__init__(simulation)`` runs when the simulation is built: check that the action
          applies (integrator, backend) and raise ``scene.error("watch.on_alarm", ...)`` if
          not; build what it needs.
        * [`after_sample`][gimwatch.simulation.alarm_actions.AlarmAction.after_sample] runs after
          every watched sample (``alarm`` is the alarm raised at that sample, or None); it returns
          ``(status, message)`` to end the run, or None. What it changed is appended to
          ``simulation.actions`` as one line.
    """

    name: ClassVar[str]

    def __init__(self, simulation: Simulation) -> None:
        self.simulation = simulation

    def after_sample(self, t: float, alarm: Alarm | None) -> tuple[str, str] | None:
        """Act on this sample; return (status, message) to stop the run."""
        return None


#: The registry: scene ``on_alarm`` name -> class.
ALARM_ACTIONS: Registry[type[AlarmAction]] = Registry("on_alarm action")


register = ALARM_ACTIONS.register
"""Class decorator: add an action to `ALARM_ACTIONS` under its ``name``."""


@register
class Warn(AlarmAction):
    """Record the alarm only."""

    name = "warn"


@register
class Stop(AlarmAction):
    """End the run at the first alarm."""

    name = "stop"

    def after_sample(self, t, alarm):
        if alarm is None:
            return None
        return (
            "stopped-on-alarm",
            f"{alarm.metric} = {alarm.value:.4g} crossed {alarm.threshold:.4g} at t = {t:.6g} s",
        )


@register
class Tighten(AlarmAction):
    """Lower rtol (and atol) as the estimate grows past the threshold."""

    name = "tighten"

    def __init__(self, simulation: Simulation) -> None:
        super().__init__(simulation)
        scene = simulation.scene
        if not simulation.integrator.tightenable:
            able = [name for name, cls in INTEGRATORS.items() if cls.tightenable]
            raise scene.error(
                "watch.on_alarm",
                f"tighten needs an adaptive integrator ({', '.join(able)}), "
                f"got {scene.integrator.method}",
            )

    def after_sample(self, t, alarm):
        """Set rtol ← max(rtol₀ · threshold / estimate, RTOL_FLOOR), atol by the same factor."""
        simulation = self.simulation
        watch, integrator = simulation.watch, simulation.integrator
        current = integrator.current_rtol()
        if current is None or watch.alarm_metric is None:  # t0 comes before the solver
            return None
        value = watch.series[watch.alarm_metric][-1]
        estimate = watch.metrics[watch.alarm_metric].severity(value)
        spec = simulation.scene.integrator
        if not estimate > watch.alarm_threshold:
            return None
        factor = max(watch.alarm_threshold / estimate, RTOL_FLOOR / spec.rtol)
        rtol = spec.rtol * factor
        if rtol >= 0.99 * current:  # only ever tighten
            return None
        simulation.actions.append(
            f"t = {t:.6g} s: {watch.alarm_metric} = {value:.4g}, rtol {current:.3g} -> {rtol:.3g}"
        )
        integrator.set_tolerances(rtol, spec.atol * factor)
        return None


@register
class SwitchBackend(AlarmAction):
    """Move the dynamics to `MOST_ACCURATE_BACKEND` at the first alarm."""

    name = "switch-backend"

    def __init__(self, simulation: Simulation) -> None:
        super().__init__(simulation)
        scene = simulation.scene
        if scene.backend == MOST_ACCURATE_BACKEND:
            raise scene.error(
                "watch.on_alarm",
                f"switch-backend moves to {MOST_ACCURATE_BACKEND}, which the scene "
                "already uses (dynamics.backend)",
            )
        self.fallback = make_backend(MOST_ACCURATE_BACKEND, simulation.robot, simulation.gravity)

    def after_sample(self, t, alarm):
        if alarm is not None and self.fallback is not None:
            simulation = self.simulation
            simulation.actions.append(
                f"t = {t:.6g} s: backend {simulation.backend.name} -> {self.fallback.name}"
            )
            simulation.backend, self.fallback = self.fallback, None
        return None
