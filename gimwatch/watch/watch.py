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
from gimwatch.metrics.mass_matrix_sources import PinocchioSource, diagonal_source
from gimwatch.metrics.registry import METRICS, GimState, Metric
from gimwatch.model.mass_matrix_source import (
    CHECK_EVERY_SAMPLE,
    CHECK_ONCE,
    MassMatrixSource,
)
from gimwatch.model.q_checks import UNIT_NORM_TOLERANCE, as_configuration, unit_blocks
from gimwatch.model.robots import DATA_NV_LIMIT, Robot
from gimwatch.watch.alarm import (
    DEFAULT_ALARM_THRESHOLD,
    Alarm,
    alarm_threshold,
    check_on_alarm,
    warn_alarm,
)
from gimwatch.watch.compiled_path import FAST_METRICS, CompiledSampler
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
#: Metrics that run the robot's RNEA/ABA at q (they declare ``needs_robot``): not M alone.
OPERATOR_METRICS = frozenset(name for name, cls in METRICS.items() if cls.needs_robot)


def _metric_names(metrics) -> tuple[str, ...]:
    names = (metrics,) if isinstance(metrics, str) else tuple(metrics)
    for name in names:
        if name not in METRICS:
            raise InputError("a watched metric", f"one of {sorted(METRICS)}", name)
    return names


def _watch_source(
    robot: Robot | None, source: MassMatrixSource | None, metrics: dict[str, Metric], full: bool
) -> MassMatrixSource:
    """The one source a watch samples: the given one, or Pinocchio's CRBA on ``robot``."""
    if robot is not None and not isinstance(robot, Robot):
        raise InputError(
            "robot",
            "a gimwatch Robot",
            type_name(robot),
            hint="Watch.from_model takes a pinocchio.Model, Watch.from_mujoco a MuJoCo pair",
        )
    if source is not None and not isinstance(source, MassMatrixSource):
        raise InputError(
            "source", "a MassMatrixSource (gimwatch.model.mass_matrix_source)", type_name(source)
        )
    if source is None:
        if robot is None:
            raise InputError("robot", "a gimwatch Robot (or a source giving nv)", None)
        # Pinocchio's Data (memory ∝ nv³) unless DeNOC serves diag M alone
        needs_data = bool(metrics) and (full or robot.nv <= DATA_NV_LIMIT)
        return PinocchioSource(robot, robot.new_data() if needs_data else None)
    for name in (n for n, m in metrics.items() if m.needs_robot and source.robot is None):
        raise InputError(
            f"metric {name!r}",
            "watched on a robot (it runs RNEA/ABA at q)",
            "a watch without one",
            hint="use Watch(robot, ...) or Watch.from_model",
        )
    return source


class Watch:
    """Evaluates the requested metrics at samples and raises alarms, in any loop.

    Build it from what the loop has: ``Watch(robot, metrics)`` (a gimwatch
    [`Robot`][gimwatch.model.robots.Robot]), [`from_model`][gimwatch.watch.watch.Watch.from_model]
    (a ``pinocchio.Model``), [`from_mujoco`][gimwatch.watch.watch.Watch.from_mujoco] (a MuJoCo
    ``MjModel``/``MjData`` pair), [`from_matrices`][gimwatch.watch.watch.Watch.from_matrices] (M
    or diag M fed by hand) or ``Watch(source=...)`` (any
    [`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource], your own too).
    Sample with [`sample`][gimwatch.watch.watch.Watch.sample] (a
    configuration ``q``), [`sample_matrix`][gimwatch.watch.watch.Watch.sample_matrix] (M) or
    [`sample_diagonal`][gimwatch.watch.watch.Watch.sample_diagonal] (diag M); read the series with
    [`array`][gimwatch.watch.watch.Watch.array], [`arrays`][gimwatch.watch.watch.Watch.arrays]
    or [`to_dataframe`][gimwatch.watch.watch.Watch.to_dataframe].

    The watch is composed of one source (where M comes from), a `CompiledSampler` (the fast
    path of κ and δ), a `WatchSeries` (the samples) and its `SeriesViews` (arrays, frames,
    figures), to which it delegates.

    Args:
        robot: The robot; None when ``source`` gives ``nv`` (MuJoCo, matrices, your own).
        metrics: Names from `METRICS`; only these are built and evaluated.
        alarm_metric: One of ``metrics`` (or None for no alarm).
        alarm_threshold: Threshold on the metric's condition-number scale; default
            `DEFAULT_ALARM_THRESHOLD` (κ·eps = 1e-2).
        on_alarm: Called with the [`Alarm`][gimwatch.watch.alarm.Alarm] at each upward crossing.
        warn: Issue [`IllConditionedWarning`][gimwatch.errors.IllConditionedWarning] at each upward
            crossing; None: when no ``on_alarm`` is given.
        source: Where M(q) and diag M(q) come from, a
            [`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource] (a
            simulation passes its backend, so that a long chain on ``denoc`` never builds a
            Pinocchio Data; see [`gimwatch.watch.sources`][gimwatch.watch.sources]);
            None: Pinocchio's CRBA on ``robot``, with a Data of its own.

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
        source: MassMatrixSource | None = None,
    ) -> None:
        names = _metric_names(metrics)
        self.metrics = {name: METRICS[name]() for name in names}
        self.full = any(m.full for m in self.metrics.values())
        source = _watch_source(robot, source, self.metrics, self.full)
        # diag M and δ by one compiled DeNOC call when M itself is not needed
        self.source = diagonal_source(source) if names and not self.full else source
        self._set_alarm(alarm_metric, alarm_threshold, on_alarm, warn)
        self.alarms: list[Alarm] = []
        self._alarm_on = False
        widths = {name: self.nv if m.vector else 0 for name, m in self.metrics.items()}
        self._series = WatchSeries(widths)
        self._views = SeriesViews(self._series, self.metrics)
        # the compiled path, once the first sample passed every check (see sample)
        fast = bool(names) and FAST_METRICS.issuperset(names)
        self._sampler = CompiledSampler(names, self.full, self.source) if fast else None
        self._checked = False
        self._given: tuple[GivenMatrix, CompiledSampler | None] | None = None
        robot = self.source.robot
        checks_q = robot is not None and self.source.check_q
        self._blocks = (*unit_blocks(robot), robot.nq) if robot and checks_q else None

    @property
    def robot(self) -> Robot | None:
        """The robot of the source (None for MuJoCo, matrices and sources without one)."""
        return self.source.robot

    @property
    def nv(self) -> int:
        """The size of M."""
        return self.source.nv

    @property
    def dof_names(self) -> tuple[str, ...]:
        """The names of M's coordinates."""
        return tuple(self.source.dof_names)

    @property
    def lean(self) -> Any:
        """DeNOC's compiled model serving diag M and δ, None when the source has none."""
        return self.source.lean_model()

    @property
    def data(self) -> Any:
        """The Pinocchio Data the source holds (None: none built, e.g. above DATA_NV_LIMIT)."""
        return self.source.pinocchio_data()

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
        return cls(None, metrics, source=source, **options)

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
        return cls(None, metrics, source=GivenMatrix(nv, dof_names), **options)

    # -- sampling --------------------------------------------------------------------------
    def sample(self, t: float, q: npt.ArrayLike | None = None) -> Alarm | None:
        """Record the watched metrics of M(q) at time ``t`` (s); return a new alarm, if any.

        ``q`` is the configuration (length nq; MuJoCo's ``qpos`` for
        [`from_mujoco`][gimwatch.watch.watch.Watch.from_mujoco], where it may be omitted to read
        the M held in ``data``).
        """
        if not self.metrics:
            return None
        if type(self.source) is GivenMatrix:  # M is handed in, never computed at q
            raise InputError(
                "sample(t, q)",
                "used on a watch of a robot or a MuJoCo pair",
                "a matrix watch",
                hint="use sample_matrix(t, M) or sample_diagonal(t, d)",
            )
        if q is None and not self.source.reads_state:
            raise InputError("q", "given (a configuration of the robot)", None)
        t = _time(t)
        point: Any = q if self._blocks is None else self._configuration(q)
        sampler = self._sampler
        values = sampler.values(point) if self._checked and sampler is not None else None
        if values is None:
            values = self._checked_values(GimState(self.source, point, full=self.full), point)
        return self._record(t, values)

    def sample_matrix(self, t: float, M: npt.ArrayLike) -> Alarm | None:
        """Record the watched metrics of the given M (nv x nv, symmetric positive definite)."""
        t = _time(t)
        given, sampler = self._hold()
        given.hold_matrix(M)
        if not self.full:  # no eigen-solve to fold the check into: M > 0 by Cholesky
            ldlt_pivots(given.gim())
        values = None if sampler is None else sampler.values(None)
        if values is None:
            state = GimState(given, None, full=self.full)
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
        given, sampler = self._hold()
        given.hold_diagonal(diagonal)
        values = None if sampler is None else sampler.values(None)
        if values is None:
            state = GimState(given, None)
            values = [metric(state) for metric in self.metrics.values()]
        return self._record(t, values)

    def _hold(self) -> tuple[GivenMatrix, CompiledSampler | None]:
        """The watch's matrix in hand and its compiled path (the watch's own for a matrix watch)."""
        for name in (n for n, m in self.metrics.items() if m.needs_robot):
            raise InputError(
                f"metric {name!r}", "sampled with q (it runs RNEA/ABA at q)", "a matrix sample"
            )
        if self._given is None:
            if isinstance(self.source, GivenMatrix):
                self._given = (self.source, self._sampler)
            else:
                given = GivenMatrix(self.nv, self.dof_names)
                sampler = self._sampler and CompiledSampler(tuple(self.metrics), self.full, given)
                self._given = (given, sampler)
        return self._given

    def _configuration(self, q) -> np.ndarray:
        """Q checked by one compiled pass when already a float vector of nq, else copied.

        The compiled path only reads q, so a good float vector is not copied; anything else
        goes through `as_configuration` (a checked copy, or the error naming the fault).
        """
        stops, sizes, _, nq = self._blocks  # type: ignore[misc]  # set when q is checked
        sampler = self._sampler
        if (
            sampler is not None
            and type(q) is np.ndarray
            and q.dtype == np.float64
            and q.shape == (nq,)
            and sampler.kernels.unit_block_fault(q, stops, sizes, UNIT_NORM_TOLERANCE) == -1
        ):
            return q
        return as_configuration(self.robot, q)  # type: ignore[arg-type]  # _blocks: a robot

    def _checked_values(self, state: GimState, q) -> list:
        """Every metric through the checked state; M > 0 checked as the source declares.

        When no metric forms M, a source's M is checked positive definite once
        (``CHECK_ONCE``: the same model and code give the same kind of M), at every sample
        (``CHECK_EVERY_SAMPLE``: MuJoCo's negative ``dof_armature``), or never
        (``GUARANTEED``).
        """
        values = [metric(state) for metric in self.metrics.values()]
        definiteness = self.source.definiteness
        if not self.full and definiteness == CHECK_EVERY_SAMPLE:
            ldlt_pivots(self.source.gim(q))  # raises ConditioningError: M is not > 0
        elif not self.full and definiteness == CHECK_ONCE and not self._checked:
            ldlt_pivots(state.M)
        self._checked = definiteness != CHECK_EVERY_SAMPLE
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
        fixed = (metric.calibration for metric in self.metrics.values())
        return next((value for value in fixed if value is not None), None)

    @property
    def times(self) -> np.ndarray:
        """The sample times (s) so far (a read-only view)."""
        return self._views.times

    @property
    def series(self) -> dict[str, np.ndarray]:
        """Name -> the watched metric's values so far (read-only views; vector metrics 2-D)."""
        return self._views.series

    def array(self, name: str) -> np.ndarray:
        """One series as an array: ``"t"`` (s) or a watched metric (vector metrics: 2-D)."""
        return self._views.array(name)

    def arrays(self) -> dict[str, np.ndarray]:
        """The series as arrays: ``watch_t``, ``watch_<metric>`` and each metric's records."""
        return self._views.arrays()

    def to_dataframe(self):
        """The series as a pandas DataFrame (see `SeriesViews.to_dataframe`)."""
        return self._views.to_dataframe()

    def plot(self, metrics: tuple[str, ...] | None = None, *, ax=None):
        """The watched scalar metrics over time, with the alarm threshold (`SeriesViews.plot`)."""
        return self._views.plot(metrics, ax=ax, alarm=(self.alarm_metric, self.alarm_threshold))

    def __repr__(self) -> str:
        """One line: the robot, the metrics, the samples taken and the alarm."""
        robot = self.robot.name if self.robot is not None else type(self.source).__name__
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
