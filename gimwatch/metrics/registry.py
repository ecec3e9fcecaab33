"""The metric registry: every conditioning metric of M(q), declared once, looked up by name.

The watch, ``analyze`` (dense and O(n) paths), the survey, the stress suite and the bench
evaluate metrics through `METRICS` on one `GimState` per configuration, built on one
[`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource]. The state computes
the expensive quantities lazily, at most once, and only when a metric asks, each from what the
source declares:

* ``M`` — the source's ``gim(q)`` (Pinocchio's CRBA, DeNOC dense, MuJoCo) or a matrix given by
  the caller; O(n²) to form;
* ``diag`` — read off M when M is needed anyway, else the source's O(n) ``gim_diagonal(q)``
  (DeNOC's compiled composite-mass recursion, MuJoCo's sparse M, DeNOC's linear-time state);
* ``eigenvalues`` (ascending) and ``eigenvectors`` — a symmetric eigen-solve of M, O(n³);
* ``extremes`` (λmin, λmax) — from the eigen-solve when the source offers no linear state,
  else from its O(n) products M·x and M⁻¹·x (no M) on the κ tracker's engine;
* ``equilibrated_extremes`` — (λmin, λmax) of S = D^-1/2 M D^-1/2 (κ_S), dense from M or by
  Lanczos on S·x and S⁻¹·x from the linear state's O(n) products and diagonal;
* ``ldlt_pivots`` / ``udut_pivots`` — from the Cholesky factor of M, or (UDUᵀ) from the O(n)
  articulated-body factor of the linear state.

Adding a metric: subclass `Metric` (set ``name`` and ``full``, and write
``__call__(state)`` reading only what it needs from the state), decorate it with
`register` (or list it in `METRICS`), and test it against an independent value;
``gimwatch metrics``, scenes, the watch and the CLI read the registry. See
``docs/contributing.md``.
"""

from __future__ import annotations

import math
from typing import Any, ClassVar

import numpy as np

from gimwatch.metrics import conditioning, equilibrated
from gimwatch.model.mass_matrix_source import LinearState, MassMatrixSource
from gimwatch.registries import Registry

__all__ = ["METRICS", "GimState", "Metric", "evaluate", "register"]


class GimState:
    """Lazily computed, shared quantities of M(q) at one configuration, from one source.

    Each quantity dispatches to what the source declares (see
    [`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource]): diag M from
    ``gim_diagonal`` unless M is formed anyway, δ from ``diagonal_ratio`` when offered, and
    λmin, λmax, κ_S and the UDUᵀ pivots from ``linear_state`` (O(n), M never formed) when
    offered, else from M.

    Args:
        source: Where M(q) comes from.
        q: The configuration (None when the source holds M itself).
        full: Whether M is formed anyway (then diag M is read off it).
        lanczos: Seed and relative tolerance of Lanczos on the source's linear state.
        matrix: M(q) of this source already formed by the caller (checked here).
    """

    def __init__(
        self,
        source: MassMatrixSource,
        q: np.ndarray | None = None,
        *,
        full: bool = False,
        lanczos: tuple[int, float] = (0, 1e-9),
        matrix: np.ndarray | None = None,
    ) -> None:
        self.source, self.q, self.full, self.lanczos = source, q, full, lanczos
        self._M: np.ndarray | None = None
        self._diag: np.ndarray | None = None
        self._eig: np.ndarray | None = None
        self._raw: np.ndarray | None = None
        self._vectors: np.ndarray | None = None
        self._extremes: tuple[float, float] | None = None
        self._equilibrated: tuple[float, float] | None = None
        self._ldlt: np.ndarray | None = None
        self._udut: np.ndarray | None = None
        self._linear: LinearState | bool | None = False  # False: not asked yet
        if matrix is not None:
            self._M = conditioning.check_gim(matrix)

    @property
    def linear(self) -> LinearState | None:
        """The source's O(n) state of M at q, None when it offers none."""
        if self._linear is False:
            self._linear = self.source.linear_state(self.q)
        return self._linear  # type: ignore[return-value]

    @property
    def M(self) -> np.ndarray:
        """The mass matrix at q, checked (finite, symmetric, positive diagonal)."""
        if self._M is None:
            self._M = conditioning.check_gim(self.source.gim(self.q))
        return self._M

    @property
    def diag(self) -> np.ndarray:
        """Diag M(q) in the source's coordinate order, O(n) unless M is formed anyway."""
        if self._diag is None:
            formed = self.full or self._M is not None
            self._diag = np.diag(self.M).copy() if formed else self.source.gim_diagonal(self.q)
        return self._diag

    @property
    def delta(self) -> float:
        """δ = max M_ii / min M_ii: one call when the source offers it and M is not formed."""
        if not self.full and self._M is None and self._diag is None:
            value = self.source.diagonal_ratio(self.q)
            if value is not None and 1.0 <= value < math.inf:  # else the checked path names it
                return value
        return conditioning.diagonal_ratio(self.diag)

    @property
    def eigenvalues(self) -> np.ndarray:
        """The spectrum of M, ascending."""
        if self._eig is None:
            self._eig = conditioning.eigenvalues(self.M)
        return self._eig

    @property
    def eigenpairs(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues as LAPACK returns them (λmin may be ≤ 0 near κ = 1/eps) and vectors.

        One ``eigh``; a positive spectrum then also serves `eigenvalues`.
        """
        if self._vectors is None or self._raw is None:
            values, self._vectors = conditioning.eigenpairs(self.M)
            self._raw = values
            if values[0] > 0:  # else `eigenvalues` judges the spectrum itself
                self._eig = values
        return self._raw, self._vectors

    @property
    def extremes(self) -> tuple[float, float]:
        """(λmin, λmax): by Lanczos on the linear state's O(n) products, or the eigen-solve."""
        if self._extremes is None:
            linear = self.linear
            self._extremes = (
                self._eigen_extremes() if linear is None else self._lanczos_extremes(linear)
            )
        return self._extremes

    def _eigen_extremes(self) -> tuple[float, float]:
        values = self.eigenvalues
        return float(values[0]), float(values[-1])

    def _lanczos_extremes(self, operator: Any) -> tuple[float, float]:
        from gimwatch.metrics.tracker.extremes import extreme_eigenvalues

        seed, rtol = self.lanczos
        found = extreme_eigenvalues(operator, seed=seed, rtol=rtol)
        return found.lambda_min, found.lambda_max

    @property
    def equilibrated_extremes(self) -> tuple[float, float]:
        """(λmin, λmax) of S = D^-1/2 M D^-1/2: Lanczos on S·x and S⁻¹·x at O(n), or dense."""
        if self._equilibrated is None:
            linear = self.linear
            self._equilibrated = (
                equilibrated.equilibrated_extremes(self.M)
                if linear is None
                else self._lanczos_extremes(equilibrated.ScaledState(linear, linear.diagonal()))
            )
        return self._equilibrated

    @property
    def ldlt_pivots(self) -> np.ndarray:
        """Pivots of M = L D Lᵀ (elimination from the root), from M's Cholesky factor."""
        if self._ldlt is None:
            self._ldlt = conditioning.ldlt_pivots(self.M)
        return self._ldlt

    @property
    def udut_pivots(self) -> np.ndarray:
        """Pivots of M = U D Uᵀ (elimination from the tips); O(n) on the linear state."""
        if self._udut is None:
            linear = self.linear
            self._udut = (
                conditioning.udut_pivots(self.M)
                if linear is None
                else self.source.to_public(linear.pivots())
            )
        return self._udut


class Metric:
    """One watched quantity.

    ``full``: needs M (not only its diagonal); ``vector``: one value per coordinate;
    ``needs_robot``: runs the robot's RNEA/ABA at q, so it needs a robot and a configuration.
    """

    name: ClassVar[str]
    full: ClassVar[bool] = True
    vector: ClassVar[bool] = False
    needs_robot: ClassVar[bool] = False

    def __call__(self, state: GimState):
        """The metric's value at the state's configuration."""
        raise NotImplementedError

    def severity(self, value: float) -> float:
        """The value on a condition-number scale (large = ill-conditioned), for alarms."""
        return value

    @property
    def calibration(self) -> float | None:
        """The constant the metric fixed at its first sample (α of αδ), None when it has none."""
        return None

    def records(self, samples: int) -> dict[str, np.ndarray]:
        """Per-sample records the metric keeps besides its value, keyed by suffix.

        A watch hands them out as ``watch_<name>_<suffix>`` beside the values when the metric
        holds one record per sample (``samples`` of them); none by default.
        """
        return {}


class Kappa(Metric):
    """κ₂ = λmax / λmin (Eq. 6)."""

    name = "kappa"

    def __call__(self, state):
        return conditioning.extreme_ratio(state.extremes)


class KappaEquilibrated(Metric):
    """κ_S = κ₂(D^-1/2 M D^-1/2), D = diag M: the digits a Cholesky solve loses, in any units."""

    name = "kappa_equilibrated"

    def __call__(self, state):
        return conditioning.extreme_ratio(state.equilibrated_extremes)


class KappaEquilibratedTracked(Metric):
    """κ_S tracked at O(n) per sample: the κ tracker on D^-1/2 M D^-1/2 (no M formed)."""

    name = "kappa_equilibrated_tracked"
    full = False
    needs_robot = True

    def __init__(self) -> None:
        self.tracker = None

    def __call__(self, state):
        if self.tracker is None:
            source = state.source
            self.tracker = equilibrated.equilibrated_tracker(
                source.robot, source, source.pinocchio_data(), source.lean_model()
            )
        return self.tracker.sample(state.q).kappa


class KappaLanczos(Metric):
    """κ₂ = λmax / λmin (Eq. 6) by low-accuracy Lanczos on O(n) products, no M formed.

    The κ tracker ([`KappaTracker`][gimwatch.metrics.tracker.KappaTracker], the one Krylov engine
    of gimwatch) at relative tolerance `TOL` on DeNOC's compiled M·x and M⁻¹·y (Pinocchio's
    RNEA/ABA when DeNOC cannot read the robot); each sample starts from the previous sample's
    extreme eigenvectors, so along a smooth trajectory a few O(n) products per sample suffice.
    """

    name = "kappa_lanczos"
    full = False
    needs_robot = True
    TOL: ClassVar[float] = 1e-3

    def __init__(self) -> None:
        self.tracker: Any = None

    def __call__(self, state):
        if self.tracker is None:
            # imported here: the compiled kernels cost a fraction of a second to import,
            # which the dense path (analyze, the watch without this metric) never pays
            from gimwatch.metrics.tracker import KappaTracker, TrackerSettings
            from gimwatch.metrics.tracker.providers import gim_products

            source = state.source
            provider = source.lean_model() or gim_products(
                source.robot, None, source.pinocchio_data()
            )
            self.tracker = KappaTracker(provider, source.nv, TrackerSettings(rtol=self.TOL))
        return self.tracker.sample(state.q).kappa


class KappaTracked(Metric):
    """κ₂ = λmax / λmin (Eq. 6) to a relative tolerance 1e-10, tracked at O(n) per sample.

    [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] on DeNOC's
    compiled M·x and M⁻¹·y (or Pinocchio's RNEA/ABA when DeNOC cannot read the robot), warm-started
    from the previous sample's eigenvectors, with a detected cold-start fallback. ``products`` lists
    the O(n) products each sample took, ``fallbacks`` each sample's fallback (``""``, ``"cold"``,
    ``"dense"``, ...) and ``error_estimates`` its relative error bound (both ends certified by
    Sylvester's law of inertia: the true κ lies in [κ, κ·(1 + bound)]). A sample the O(n)
    solve cannot converge or certify falls back to a dense eigen-solve of M (Pinocchio's CRBA or
    the backend's ``gim``) instead of raising.
    """

    name = "kappa_tracked"
    full = False
    needs_robot = True

    def __init__(self) -> None:
        self.tracker = None
        self.products: list[int] = []
        self.fallbacks: list[str] = []
        self.error_estimates: list[float] = []

    def __call__(self, state):
        if self.tracker is None:
            from gimwatch.metrics.tracker import KappaTracker
            from gimwatch.metrics.tracker.providers import gim_products

            source = state.source
            provider = source.lean_model() or gim_products(
                source.robot, None, source.pinocchio_data()
            )
            self.tracker = KappaTracker(provider, source.nv, dense=source.gim)
        result = self.tracker.sample(state.q)
        self.products.append(result.products)
        self.fallbacks.append(result.fallback)
        self.error_estimates.append(float(result.error_estimate))
        return result.kappa

    def records(self, samples: int) -> dict[str, np.ndarray]:
        """Each sample's fallback and relative error bound, when every sample has one."""
        if len(self.fallbacks) != samples:
            return {}
        return {
            "fallback": np.array(self.fallbacks, dtype=str),
            "error_estimate": np.array(self.error_estimates),
        }


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

    @property
    def calibration(self) -> float | None:
        """α = κ(t0)/δ(t0), once the first sample fixed it."""
        return self.estimator.alpha

    def __call__(self, state):
        if not self.estimator.calibrated:  # t0: κ from the state, shared with a watched κ
            kappa = conditioning.extreme_ratio(state.extremes)
            alpha = kappa / conditioning.diagonal_ratio(state.diag)
            self.estimator = conditioning.ScaledDiagonalRatio(alpha=alpha)
        return self.estimator.alpha * state.delta  # Eq. 15 on the O(n) δ


class PivotRatioForward(Metric):
    """max/min LDLᵀ pivot (the paper's Gaussian elimination, Fig. 4)."""

    name = "pivot_ratio_forward"

    def __call__(self, state):
        return conditioning.extreme_ratio(state.ldlt_pivots)


class PivotRatioBackward(Metric):
    """max/min UDUᵀ pivot (elimination from the tips)."""

    name = "pivot_ratio_backward"

    def __call__(self, state):
        return conditioning.extreme_ratio(state.udut_pivots)


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


class StabilityMargin(Metric):
    """h/h*: the robot's timestep over the largest stable one of its integrator, at q.

    For an MJCF robot with servos (`gimwatch.stability`): the file's actuators, joint springs
    and dampers, ``<option timestep integrator>``, and gravity's stiffness at q; M is the
    sample's M (armature in). Above 1 the integration is unstable there (alarm threshold 1).
    Each sample scans and bisects h (hundreds of 2nv × 2nv eigen-solves): sample sparingly.
    """

    name = "stability_margin"
    needs_robot = True

    def __init__(self) -> None:
        self.servos = None
        self.data = None

    def __call__(self, state):
        # imported here: only a watch of this metric pays for the stability package
        from gimwatch.stability.analysis import DEFAULT_TIMESTEP_S
        from gimwatch.stability.linear_system import LinearSystem, linearise
        from gimwatch.stability.timestep import max_stable_timestep

        robot = state.source.robot
        if self.servos is None:
            self.servos, self.data = _file_servos(robot, state.q), robot.new_data()
        servos = self.servos
        held = linearise(robot.model, servos, state.q, data=self.data, source=robot.source)
        system = LinearSystem(state.M, held.stiffness, held.explicit_damping, held.joint_damping)
        h_star = max_stable_timestep(system, servos.integrator or "Euler")
        h = servos.timestep_s or DEFAULT_TIMESTEP_S
        return h / h_star if h_star > 0 else math.inf


def _file_servos(robot, q):
    """The servos of an MJCF robot's file, holding q (refused for other robots)."""
    from gimwatch.errors import InputError
    from gimwatch.model.mjcf_compiled import compile_mjcf
    from gimwatch.stability.analysis import held_controls
    from gimwatch.stability.servos import mjcf_servos

    if robot is None or not robot.mujoco_joints or q is None:
        raise InputError(
            "metric 'stability_margin'", "watched on an MJCF robot with its q", "another watch"
        )
    mj_model = compile_mjcf(robot.source)
    if mj_model.nu == 0:
        raise InputError("metric 'stability_margin'", "watched on a robot with actuators", 0)
    return mjcf_servos(robot, mj_model, held_controls(mj_model, q))


#: The registry: metric name -> class.
METRICS: Registry[type[Metric]] = Registry(
    "metric",
    (
        Kappa,
        KappaEquilibrated,
        KappaEquilibratedTracked,
        KappaLanczos,
        KappaTracked,
        DiagonalRatio,
        ScaledDiagonalRatioMetric,
        PivotRatioForward,
        PivotRatioBackward,
        Rcond,
        Eigenvalues,
        Diagonal,
        StabilityMargin,
    ),
)

register = METRICS.register
"""Class decorator: add a metric to `METRICS` under its ``name``."""


def evaluate(names, state: GimState, metrics: dict[str, Metric] | None = None) -> dict:
    """The named metrics at one state: ``{name: value}``; ``metrics`` keeps their instances."""
    metrics = {} if metrics is None else metrics
    for name in names:
        if name not in metrics:
            metrics[name] = METRICS[name]()
    return {name: metrics[name](state) for name in names}
