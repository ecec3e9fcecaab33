"""The GIM watch: the requested conditioning metrics of M(q) at sample times, and alarms.

Metrics come from :data:`METRICS`, keyed by the scene's names; a metric nobody watches is
never built, so its cost is never paid. Per sample, the expensive quantities are computed
at most once and only when a watched metric needs them:

* ``diag M`` — from :func:`gimwatch.model.inertia.gim_diagonal` (O(n), no M formed) when no
  watched metric needs the full matrix, else read off M;
* ``M`` — from Pinocchio's CRBA (:func:`gimwatch.model.inertia.gim`), O(n²);
* the spectrum — a symmetric eigen-solve, O(n³), only for ``kappa`` / ``eigenvalues``
  (and once, at t0, to calibrate α of ``scaled_diagonal_ratio``, Shah & Saha 2013 Eq. 15).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from gimwatch.metrics import conditioning
from gimwatch.metrics.estimator_quality import EstimatorQuality, estimator_quality
from gimwatch.metrics.matrix_free import kappa_matrix_free
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.robots import Robot

__all__ = ["METRICS", "Alarm", "EstimatorQuality", "Watch", "estimator_quality"]


class _GimState:
    """Lazily computed, shared per-sample quantities of M(q)."""

    def __init__(
        self, robot: Robot, data, q: np.ndarray, full: bool, dynamics=None, lean=None
    ) -> None:
        self.robot, self.data, self.q, self.full = robot, data, q, full
        self.dynamics, self.lean = dynamics, lean
        self._M = self._diag = self._eig = None

    @property
    def M(self) -> np.ndarray:
        if self._M is None:
            M = (
                gim(self.robot, self.q, data=self.data)
                if self.dynamics is None
                else self.dynamics.gim(self.q)
            )
            self._M = conditioning.check_gim(M)
        return self._M

    @property
    def diag(self) -> np.ndarray:
        if self._diag is None:
            self._diag = (
                np.diag(self.M).copy()
                if self.full
                else self.lean.gim_diagonal(self.q)  # one compiled call, buffers kept
                if self.lean is not None
                else gim_diagonal(self.robot, self.q, data=self.data)
                if self.dynamics is None
                else self.dynamics.gim_diagonal(self.q)
            )
        return self._diag

    @property
    def delta(self) -> float:
        """δ = max M_ii / min M_ii: one compiled call when DeNOC's lean model serves diag M."""
        if self.lean is not None and not self.full and self._diag is None:
            value = self.lean.diagonal_ratio(self.q)
            if 1.0 <= value < math.inf:  # else the checked path below names the problem
                return value
        return conditioning.diagonal_ratio(self.diag)

    @property
    def eigenvalues(self) -> np.ndarray:
        if self._eig is None:
            self._eig = conditioning.eigenvalues(self.M)
        return self._eig


class Metric:
    """One watched quantity. ``full``: needs M (not only its diagonal)."""

    name: ClassVar[str]
    full: ClassVar[bool] = True
    vector: ClassVar[bool] = False

    def __call__(self, state: _GimState):
        raise NotImplementedError

    def severity(self, value: float) -> float:
        """The value on a condition-number scale (large = ill-conditioned), for alarms."""
        return value


class Kappa(Metric):
    """κ₂ = λmax / λmin (Eq. 6)."""

    name = "kappa"

    def __call__(self, state):
        values = state.eigenvalues
        return float(values[-1] / values[0])


class KappaLanczos(Metric):
    """κ₂ = λmax / λmin (Eq. 6) by low-accuracy Lanczos on the RNEA and ABA operators.

    No M is formed (:func:`gimwatch.metrics.matrix_free.kappa_matrix_free`, ARPACK tolerance
    :attr:`TOL`); each sample starts from the previous sample's extreme eigenvectors, so
    along a smooth trajectory a few O(n) products per sample suffice.
    """

    name = "kappa_lanczos"
    full = False
    TOL: ClassVar[float] = 1e-3

    def __init__(self) -> None:
        self.start: tuple[np.ndarray, np.ndarray] | None = None
        self.data = None

    def __call__(self, state):
        if self.data is None:  # RNEA/ABA need a Pinocchio Data, even when M comes from DeNOC
            self.data = state.robot.new_data() if state.data is None else state.data
        result = kappa_matrix_free(
            state.robot, state.q, data=self.data, seed=0, tol=self.TOL, start=self.start
        )
        self.start = (result.vector_max, result.vector_min)
        return result.kappa


class KappaTracked(Metric):
    """κ₂ = λmax / λmin (Eq. 6) to a relative tolerance 1e-10, tracked at O(n) per sample.

    :class:`gimwatch.metrics.tracker.KappaTracker` on DeNOC's compiled M·x and M⁻¹·y (or
    Pinocchio's RNEA/ABA when DeNOC cannot read the robot), warm-started from the previous
    sample's eigenvectors, with a detected cold-start fallback. ``products`` lists the O(n)
    products each sample took.
    """

    name = "kappa_tracked"
    full = False

    def __init__(self) -> None:
        self.tracker = None
        self.products: list[int] = []

    def __call__(self, state):
        if self.tracker is None:
            from gimwatch.metrics.tracker import KappaTracker
            from gimwatch.metrics.tracker_providers import gim_products

            provider = state.lean or gim_products(state.robot, state.dynamics, state.data)
            self.tracker = KappaTracker(provider, state.robot.nv)
        result = self.tracker.sample(state.q)
        self.products.append(result.products)
        return result.kappa


class DiagonalRatio(Metric):
    """δ = max M_ii / min M_ii (Sec. 4), from the O(n) diagonal."""

    name = "diagonal_ratio"
    full = False

    def __call__(self, state):
        return state.delta


class ScaledDiagonalRatioMetric(Metric):
    """αδ with α = κ(t0)/δ(t0) fixed at the first sample (Eq. 15)."""

    name = "scaled_diagonal_ratio"
    full = False

    def __init__(self) -> None:
        self.estimator = conditioning.ScaledDiagonalRatio()

    def __call__(self, state):
        if not self.estimator.calibrated:
            self.estimator.calibrate(state.M)
            return self.estimator(state.diag)
        return self.estimator.alpha * state.delta  # Eq. 15 on the O(n) δ


class PivotRatioForward(Metric):
    """max/min LDLᵀ pivot (the paper's Gaussian elimination, Fig. 4)."""

    name = "pivot_ratio_forward"

    def __call__(self, state):
        return conditioning.pivot_ratio_forward(state.M)


class PivotRatioBackward(Metric):
    """max/min UDUᵀ pivot (elimination from the tips)."""

    name = "pivot_ratio_backward"

    def __call__(self, state):
        return conditioning.pivot_ratio_backward(state.M)


class Rcond(Metric):
    """LAPACK's reciprocal condition estimate 1/κ₁ (``dpocon``)."""

    name = "rcond"

    def __call__(self, state):
        return 1.0 / conditioning.condition_estimate_1norm(state.M)

    def severity(self, value: float) -> float:
        return 1.0 / value


class Eigenvalues(Metric):
    """The spectrum of M, ascending (Fig. 2a)."""

    name = "eigenvalues"
    vector = True

    def __call__(self, state):
        return state.eigenvalues.copy()


class Diagonal(Metric):
    """diag M in Pinocchio's coordinate order (Fig. 2b)."""

    name = "diagonal"
    full = False
    vector = True

    def __call__(self, state):
        return state.diag.copy()


#: The registry: scene metric name -> class.
METRICS: dict[str, type[Metric]] = {
    cls.name: cls
    for cls in (
        Kappa,
        KappaLanczos,
        KappaTracked,
        DiagonalRatio,
        ScaledDiagonalRatioMetric,
        PivotRatioForward,
        PivotRatioBackward,
        Rcond,
        Eigenvalues,
        Diagonal,
    )
}


@dataclass(frozen=True)
class Alarm:
    """The alarm metric crossed its threshold at ``time_s`` (upward crossing)."""

    time_s: float
    metric: str
    value: float
    threshold: float


class Watch:
    """Evaluates the requested metrics at samples and raises alarms.

    Args:
        robot: The robot.
        metrics: Names from :data:`METRICS`; only these are built and evaluated.
        alarm_metric: One of ``metrics`` (or None for no alarm).
        alarm_threshold: Threshold on the metric's condition-number scale.
        dynamics: Where M(q) and diag M(q) come from: an object with ``gim(q)`` and
            ``gim_diagonal(q)`` (a simulation passes its backend, so that a long chain on
            ``denoc`` never builds a Pinocchio Data); None: Pinocchio, with a Data of its own.
    """

    def __init__(
        self,
        robot: Robot,
        metrics: tuple[str, ...] = (),
        *,
        alarm_metric: str | None = None,
        alarm_threshold: float | None = None,
        dynamics=None,
    ) -> None:
        self.robot = robot
        self.dynamics = dynamics
        self.metrics = {name: METRICS[name]() for name in metrics}
        self.full = any(m.full for m in self.metrics.values())
        self.data = robot.new_data() if self.metrics and dynamics is None else None
        # diag M by one compiled DeNOC call (preallocated buffers) when M itself is not needed
        self.lean = None
        if self.metrics and not self.full:
            from gimwatch.metrics.tracker_providers import lean_model

            self.lean = lean_model(robot, dynamics)
        self.alarm_metric, self.alarm_threshold = alarm_metric, alarm_threshold
        self.times: list[float] = []
        self.series: dict[str, list] = {name: [] for name in self.metrics}
        self.alarms: list[Alarm] = []
        self._alarm_on = False

    def sample(self, t: float, q: np.ndarray) -> Alarm | None:
        """Record the watched metrics at time ``t`` (s); return a new alarm, if one is raised."""
        if not self.metrics:
            return None
        state = _GimState(self.robot, self.data, q, self.full, self.dynamics, self.lean)
        self.times.append(float(t))
        for name, metric in self.metrics.items():
            self.series[name].append(metric(state))
        if self.alarm_metric is None:
            return None
        value = self.series[self.alarm_metric][-1]
        above = self.metrics[self.alarm_metric].severity(value) > self.alarm_threshold
        alarm = None
        if above and not self._alarm_on:
            alarm = Alarm(float(t), self.alarm_metric, float(value), float(self.alarm_threshold))
            self.alarms.append(alarm)
        self._alarm_on = above
        return alarm

    @property
    def alpha(self) -> float | None:
        """α of the scaled diagonal ratio, when watched and calibrated."""
        metric = self.metrics.get("scaled_diagonal_ratio")
        return None if metric is None else metric.estimator.alpha

    def arrays(self) -> dict[str, np.ndarray]:
        """The series as arrays, keyed ``watch_<metric>`` plus ``watch_t``."""
        out = {"watch_t": np.asarray(self.times, dtype=float)}
        for name, values in self.series.items():
            out[f"watch_{name}"] = np.asarray(values, dtype=float)
        return out
