"""The GIM watch: the requested conditioning metrics of M(q) at sample times, and alarms.

Metrics come from `METRICS`, keyed by the scene's names; a metric nobody watches is
never built, so its cost is never paid. Per sample, the expensive quantities are computed
at most once and only when a watched metric needs them:

* ``diag M`` — from [`gim_diagonal`][gimwatch.model.inertia.gim_diagonal]
  (O(n), no M formed) when no watched metric needs the full matrix, else read off M;
* ``M`` — from Pinocchio's CRBA ([`gim`][gimwatch.model.inertia.gim]), O(n²);
* the spectrum — a symmetric eigen-solve, O(n³), only for ``kappa`` / ``eigenvalues``
  (and once, at t0, to calibrate α of ``scaled_diagonal_ratio``, Shah & Saha 2013 Eq. 15).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.metrics.conditioning import ldlt_pivots
from gimwatch.metrics.estimator_quality import EstimatorQuality, estimator_quality
from gimwatch.metrics.registry import METRICS, GimState
from gimwatch.model.q_checks import UNIT_NORM_TOLERANCE, as_configuration, unit_blocks
from gimwatch.model.robots import DATA_NV_LIMIT, Robot
from gimwatch.watch.alarm import (
    DEFAULT_ALARM_THRESHOLD,
    Alarm,
    alarm_threshold,
    check_on_alarm,
    warn_alarm,
)
from gimwatch.watch.compiled_path import CompiledSampling
from gimwatch.watch.series import WatchSeries
from gimwatch.watch.series_views import SeriesViews
from gimwatch.watch.sources import GivenMatrix, MujocoSource, robot_from_model, type_name

__all__ = [
    "DEFAULT_ALARM_THRESHOLD",
    "DEFAULT_METRICS",
    "METRICS",
    "OPERATOR_METRICS",
    "EstimatorQuality",
    "Watch",
    "estimator_quality",
]


#: Watched when a constructor is given no metric names: κ (Eq. 6) and δ (Sec. 4).
DEFAULT_METRICS = ("kappa", "diagonal_ratio")
#: Metrics that run the robot's RNEA/ABA at q: they need a robot and a configuration, not M.
OPERATOR_METRICS = frozenset(
    {"kappa_lanczos", "kappa_tracked", "kappa_equilibrated_tracked", "stability_margin"}
)
#: Metrics of the compiled sample path: one scaled eigen-solve, or the diagonal alone.
FAST_METRICS = frozenset({"kappa", "eigenvalues", "diagonal_ratio", "diagonal"})


def _metric_names(metrics) -> tuple[str, ...]:
    names = (metrics,) if isinstance(metrics, str) else tuple(metrics)
    for name in names:
        if name not in METRICS:
            raise InputError("a watched metric", f"one of {sorted(METRICS)}", name)
    return names


class Watch(CompiledSampling, SeriesViews):
    """Evaluates the requested metrics at samples and raises alarms, in any loop.

    Build it from what the loop has: ``Watch(robot, metrics)`` (a gimwatch
    [`Robot`][gimwatch.model.robots.Robot]), [`from_model`][gimwatch.watch.watch.Watch.from_model]
    (a ``pinocchio.Model``), [`from_mujoco`][gimwatch.watch.watch.Watch.from_mujoco] (a MuJoCo
    ``MjModel``/``MjData`` pair) or [`from_matrices`][gimwatch.watch.watch.Watch.from_matrices] (M
    or diag M fed by hand). Sample with [`sample`][gimwatch.watch.watch.Watch.sample] (a
    configuration ``q``), [`sample_matrix`][gimwatch.watch.watch.Watch.sample_matrix] (M) or
    [`sample_diagonal`][gimwatch.watch.watch.Watch.sample_diagonal] (diag M); read the series with
    [`array`][gimwatch.watch.watch.Watch.array], [`arrays`][gimwatch.watch.watch.Watch.arrays]
    or [`to_dataframe`][gimwatch.watch.watch.Watch.to_dataframe].

    Args:
        robot: The robot; None when ``dynamics`` is a source that gives ``nv`` (MuJoCo, matrices).
        metrics: Names from `METRICS`; only these are built and evaluated.
        alarm_metric: One of ``metrics`` (or None for no alarm).
        alarm_threshold: Threshold on the metric's condition-number scale; default
            `DEFAULT_ALARM_THRESHOLD` (κ·eps = 1e-2).
        on_alarm: Called with the [`Alarm`][gimwatch.watch.alarm.Alarm] at each upward crossing.
        warn: Issue [`IllConditionedWarning`][gimwatch.errors.IllConditionedWarning] at each upward
            crossing; None: when no ``on_alarm`` is given.
        dynamics: Where M(q) and diag M(q) come from: an object with ``gim(q)`` and
            ``gim_diagonal(q)`` (a simulation passes its backend, so that a long chain on
            ``denoc`` never builds a Pinocchio Data; see
            [`gimwatch.watch.sources`][gimwatch.watch.sources]);
            None: Pinocchio, with a Data of its own.

    Raises:
        InputError: An unknown metric, a wrong type, an alarm on an unwatched metric.
    """

    def __init__(
        self,
        robot: Robot | None = None,
        metrics: tuple[str, ...] = (),
        *,
        alarm_metric: str | None = None,
        alarm_threshold: float | None = None,
        on_alarm: Callable[[Alarm], object] | None = None,
        warn: bool | None = None,
        dynamics=None,
    ) -> None:
        names = _metric_names(metrics)
        if robot is None:
            if dynamics is None or not hasattr(dynamics, "nv"):
                raise InputError("robot", "a gimwatch Robot (or a source giving nv)", None)
            for name in OPERATOR_METRICS.intersection(names):
                raise InputError(
                    f"metric {name!r}",
                    "watched on a robot (it runs RNEA/ABA at q)",
                    "a watch without one",
                    hint="use Watch(robot, ...) or Watch.from_model",
                )
        elif not isinstance(robot, Robot):
            raise InputError(
                "robot",
                "a gimwatch Robot",
                type_name(robot),
                hint="Watch.from_model takes a pinocchio.Model, Watch.from_mujoco a MuJoCo pair",
            )
        self.robot, self.dynamics = robot, dynamics
        self.nv = robot.nv if robot is not None else int(dynamics.nv)
        self.dof_names = robot.dof_names if robot is not None else tuple(dynamics.dof_names)
        self.metrics = {name: METRICS[name]() for name in names}
        self.full = any(m.full for m in self.metrics.values())
        # diag M by one compiled DeNOC call (preallocated buffers) when M itself is not needed
        # (a source's own diag M and δ when it has them: MuJoCo's sparse M, a held matrix)
        self.lean = None
        readable = robot is not None and (robot.urdf_xml or robot.chain is not None)
        if not self.metrics or self.full:
            pass
        elif robot is None:
            self.lean = dynamics if hasattr(dynamics, "diagonal_ratio") else None
        elif readable or getattr(dynamics, "lean", None) is not None:
            from gimwatch.metrics.tracker.providers import lean_model

            self.lean = lean_model(robot, dynamics)
        # Pinocchio's Data (memory ∝ nv³) unless DeNOC serves a robot too long for it
        needs_data = self.metrics and dynamics is None and robot is not None
        if needs_data and self.lean is not None and robot.nv > DATA_NV_LIMIT:
            needs_data = False  # a metric that still needs Data says so when it runs
        self.data = robot.new_data() if needs_data else None
        self._set_alarm(alarm_metric, alarm_threshold, on_alarm, warn)
        self._check_q = robot is not None and dynamics is None
        self._given = None
        widths = {name: self.nv if m.vector else 0 for name, m in self.metrics.items()}
        self._series = WatchSeries(widths)
        self.alarms: list[Alarm] = []
        self._alarm_on = False
        # the compiled path, once the first sample passed every check (see _fast_values)
        self._fast = bool(self.metrics) and FAST_METRICS.issuperset(self.metrics)
        self._names = tuple(self.metrics)
        from gimwatch.model import kernels  # numba, imported when a watch is built, not before
        from gimwatch.model.spectrum_solver import SpectrumSolver

        self._kernels = kernels
        self._only_kappa = self._names == ("kappa",)
        self._solver = SpectrumSolver(self.nv) if self._fast and self.full else None
        self._blocks = (*unit_blocks(robot), robot.nq) if self._check_q else None
        self._matrix_watch = isinstance(dynamics, GivenMatrix)
        self._reads_state = bool(getattr(dynamics, "reads_state", False))
        self._checked = False
        self._M = np.empty((self.nv, self.nv)) if self.full else None

    def _set_alarm(self, metric, threshold, on_alarm, warn) -> None:
        if metric is not None and (metric not in self.metrics or self.metrics[metric].vector):
            scalars = [n for n, m in self.metrics.items() if not m.vector]
            raise InputError("alarm_metric", f"one of the watched scalar metrics {scalars}", metric)
        check_on_alarm(on_alarm)
        self.alarm_metric, self.alarm_threshold = metric, alarm_threshold(threshold)
        self.on_alarm = on_alarm
        self.warn = on_alarm is None if warn is None else bool(warn)

    # -- constructors ----------------------------------------------------------------------
    @classmethod
    def from_model(
        cls, model: pin.Model, metrics: tuple[str, ...] = DEFAULT_METRICS, **options: Any
    ) -> Watch:
        """A watch on a ``pinocchio.Model`` (M from Pinocchio's CRBA; δ without forming M).

        Sample with [`sample`][gimwatch.watch.watch.Watch.sample] (``q`` of length ``model.nq``).
        ``options``: the alarm arguments of [`Watch`][gimwatch.watch.watch.Watch]
        (``alarm_metric``, ``alarm_threshold``, ``on_alarm``, ``warn``).
        """
        return cls(robot_from_model(model), metrics, **options)

    @classmethod
    def from_mujoco(
        cls,
        model,
        data,
        metrics: tuple[str, ...] = DEFAULT_METRICS,
        *,
        robot: Robot | pin.Model | None = None,
        armature: bool = True,
        **options: Any,
    ) -> Watch:
        """A watch on a MuJoCo ``MjModel``/``MjData`` pair (M from ``mujoco.mj_fullM``).

        ``sample(t)`` reads the M that MuJoCo holds in ``data`` (after ``mj_step``: M where
        the step started); ``sample(t, qpos)`` computes M at ``qpos`` without touching
        ``data``. ``robot`` (a gimwatch Robot or ``pinocchio.Model``) maps MuJoCo's joints by
        name into its coordinates; ``armature=False`` removes MuJoCo's ``dof_armature`` from
        the diagonal (see [`MujocoSource`][gimwatch.watch.sources.MujocoSource]).
        ``options``: the alarm arguments of [`Watch`][gimwatch.watch.watch.Watch].
        """
        source = MujocoSource(model, data, robot=robot, armature=armature)
        return cls(None, metrics, dynamics=source, **options)

    @classmethod
    def from_matrices(
        cls,
        nv: int,
        metrics: tuple[str, ...] = DEFAULT_METRICS,
        *,
        dof_names: tuple[str, ...] | None = None,
        **options: Any,
    ) -> Watch:
        """A watch fed by hand: `sample_matrix` (M) or `sample_diagonal` (diag M).

        ``options``: the alarm arguments of [`Watch`][gimwatch.watch.watch.Watch].
        """
        return cls(None, metrics, dynamics=GivenMatrix(nv, dof_names), **options)

    # -- sampling --------------------------------------------------------------------------
    def sample(self, t: float, q: npt.ArrayLike | None = None) -> Alarm | None:
        """Record the watched metrics of M(q) at time ``t`` (s); return a new alarm, if any.

        ``q`` is the configuration (length nq; MuJoCo's ``qpos`` for
        [`from_mujoco`][gimwatch.watch.watch.Watch.from_mujoco], where it may be omitted to read
        the M held in ``data``).
        """
        if not self.metrics:
            return None
        if self._matrix_watch:
            raise InputError(
                "sample(t, q)",
                "used on a watch of a robot or a MuJoCo pair",
                "a matrix watch",
                hint="use sample_matrix(t, M) or sample_diagonal(t, d)",
            )
        if q is None and not self._reads_state:
            raise InputError("q", "given (a configuration of the robot)", None)
        t = _time(t)
        if self._check_q:
            q = self._configuration(q)
        values = self._fast_values(self.dynamics, q) if self._checked else None
        if values is None:
            state = GimState(self.robot, self.data, q, self.full, self.dynamics, self.lean)
            values = self._checked_values(state, self.dynamics, q)
        return self._record(t, values)

    def sample_matrix(self, t: float, M: npt.ArrayLike) -> Alarm | None:
        """Record the watched metrics of the given M (nv x nv, symmetric positive definite)."""
        t = _time(t)
        given = self._hold()
        given.hold_matrix(M)
        if not self.full:  # no eigen-solve to fold the check into: M > 0 by Cholesky
            ldlt_pivots(given.gim())
        values = self._fast_values(given, None)
        if values is None:
            state = GimState(self.robot, None, None, self.full, given, None)
            values = [metric(state) for metric in self.metrics.values()]
        return self._record(t, values)

    def sample_diagonal(self, t: float, diagonal: npt.ArrayLike) -> Alarm | None:
        """Record the watched metrics of the given diag M (only metrics that need no more)."""
        for name, metric in self.metrics.items():
            if metric.full:
                raise InputError(
                    "sample_diagonal", "used when no watched metric needs the full M", name
                )
        t = _time(t)
        given = self._hold()
        given.hold_diagonal(diagonal)
        values = self._fast_values(given, None)
        if values is None:
            state = GimState(self.robot, None, None, False, given, given)
            values = [metric(state) for metric in self.metrics.values()]
        return self._record(t, values)

    def _hold(self) -> GivenMatrix:
        for name in OPERATOR_METRICS.intersection(self.metrics):
            raise InputError(
                f"metric {name!r}", "sampled with q (it runs RNEA/ABA at q)", "a matrix sample"
            )
        if self._given is None:
            self._given = self.dynamics if isinstance(self.dynamics, GivenMatrix) else None
            self._given = self._given or GivenMatrix(self.nv, self.dof_names)
        return self._given

    def _configuration(self, q) -> np.ndarray:
        """Q checked by one compiled pass when already a float vector of nq, else copied.

        The compiled path only reads q, so a good float vector is not copied; anything else
        goes through `as_configuration` (a checked copy, or the error naming the fault).
        """
        stops, sizes, _, nq = self._blocks
        if (
            self._fast
            and type(q) is np.ndarray
            and q.dtype == np.float64
            and q.shape == (nq,)
            and self._kernels.unit_block_fault(q, stops, sizes, UNIT_NORM_TOLERANCE) == -1
        ):
            return q
        return as_configuration(self.robot, q)

    def _checked_values(self, state: GimState, source, q) -> list:
        """Every metric through the checked state; the first sample also checks M > 0.

        A source's own M cannot change kind between samples (the same model, the same
        code), so its checks run once per watch; a source that says its M may not be
        positive definite (``trusted = False``: MuJoCo's negative ``dof_armature``) is
        checked at every sample.
        """
        values = [metric(state) for metric in self.metrics.values()]
        if not self.full and not getattr(source, "trusted", True):
            ldlt_pivots(source.gim(q))  # raises ConditioningError: M is not > 0
        elif not self.full and source is None and self.lean is None and not self._checked:
            if self.nv <= DATA_NV_LIMIT:
                ldlt_pivots(state.M)
        self._checked = getattr(source, "trusted", True)
        return values

    def _record(self, t: float, values: list) -> Alarm | None:
        self._series.append(t, values)
        if self.alarm_metric is None:
            return None
        value = self._series.last(self.alarm_metric)
        above = self.metrics[self.alarm_metric].severity(value) > self.alarm_threshold
        alarm = None
        if above and not self._alarm_on:
            alarm = Alarm(float(t), self.alarm_metric, float(value), self.alarm_threshold)
            self.alarms.append(alarm)
        self._alarm_on = above
        if alarm is not None:
            if self.warn:
                warn_alarm(alarm, stacklevel=3)
            if self.on_alarm is not None:
                self.on_alarm(alarm)
        return alarm

    # -- results ---------------------------------------------------------------------------
    @property
    def alpha(self) -> float | None:
        """α of the scaled diagonal ratio, when watched and calibrated."""
        metric = self.metrics.get("scaled_diagonal_ratio")
        return None if metric is None else metric.estimator.alpha

    def __repr__(self) -> str:
        """One line: the robot, the metrics, the samples taken and the alarm."""
        robot = self.robot.name if self.robot is not None else type(self.dynamics).__name__
        alarm = (
            f", alarm={self.alarm_metric} > {self.alarm_threshold:.3g}"
            if self.alarm_metric is not None
            else ""
        )
        return (
            f"Watch(robot={robot!r}, metrics={list(self.metrics)}, samples={len(self.times)}, "
            f"alarms={len(self.alarms)}{alarm})"
        )


def _time(t) -> float:
    try:
        t = float(t)
    except (TypeError, ValueError):
        raise InputError("t", "a time in seconds", t) from None
    if not -math.inf < t < math.inf:
        raise InputError("t", "a finite time in seconds", t)
    return t
