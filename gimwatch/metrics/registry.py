"""The metric registry: every conditioning metric of M(q), declared once, looked up by name.

The watch, ``analyze`` (dense and O(n) paths), the survey, the stress suite and the bench
evaluate metrics through `METRICS` on one `GimState` per configuration. The
state computes the expensive quantities lazily, at most once, and only when a metric asks:

* ``M`` — Pinocchio's CRBA ([`gim`][gimwatch.model.inertia.gim]), a dynamics
  backend's ``gim(q)`` (DeNOC dense, MuJoCo) or a matrix given by the caller; O(n²) to form;
* ``diag`` — read off M when M is needed anyway, else O(n) without M: DeNOC's compiled
  composite-mass recursion (one call, buffers kept), the backend's ``gim_diagonal(q)``, or
  DeNOC's linear-time state;
* ``eigenvalues`` (ascending) and ``eigenvectors`` — a symmetric eigen-solve of M, O(n³);
* ``extremes`` (λmin, λmax) — from the eigen-solve when M is formed, else from the O(n)
  products of DeNOC's linear-time state (no M) on the κ tracker's engine;
* ``equilibrated_extremes`` — (λmin, λmax) of S = D^-1/2 M D^-1/2 (κ_S), dense from M or by
  Lanczos on S·x and S⁻¹·x from the linear state's O(n) products and diagonal;
* ``ldlt_pivots`` / ``udut_pivots`` — from the Cholesky factor of M, or (UDUᵀ) from the O(n)
  articulated-body factor of the linear-time state.

Adding a metric: subclass `Metric` (set ``name`` and ``full``, and write
``__call__(state)`` reading only what it needs from the state), decorate it with
`register` (or list it in `METRICS`), and test it against an independent value;
``gimwatch metrics``, scenes, the watch and the CLI read the registry. See
``docs/contributing.md``.
"""

from __future__ import annotations

import math
from typing import ClassVar

import numpy as np

from gimwatch.errors import ConditioningError
from gimwatch.metrics import conditioning, equilibrated
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.registries import Registry

__all__ = ["METRICS", "GimState", "Metric", "evaluate", "register"]


class GimState:
    """Lazily computed, shared quantities of M(q) at one configuration.

    Args:
        robot: The gimwatch Robot (None when M comes from elsewhere).
        data: A Pinocchio Data for CRBA (None: M from ``dynamics`` or the linear state).
        q: The configuration (None when M or diag M is given).
        full: Whether M is formed anyway (then diag M is read off it).
        dynamics: An object with ``gim(q)`` and ``gim_diagonal(q)`` giving M and diag M.
        lean: DeNOC's compiled lean model (``gim_diagonal(q)``, ``diagonal_ratio(q)``).
        linear: DeNOC's linear-time configuration state (``diagonal()``, ``pivots()``,
            ``matvec``, ``solve``): the O(n) path, on which M is never formed.
        lanczos: Seed and relative tolerance of Lanczos on the linear state.
        matrix: M(q) already formed by the caller (checked here).
        to_public: Maps a vector of the linear state's (body) order to public order.
    """

    def __init__(
        self,
        robot=None,
        data=None,
        q: np.ndarray | None = None,
        full: bool = False,
        dynamics=None,
        lean=None,
        *,
        linear=None,
        lanczos: tuple[int, float] = (0, 1e-9),
        matrix: np.ndarray | None = None,
        to_public=None,
    ) -> None:
        self.robot, self.data, self.q, self.full = robot, data, q, full
        self.dynamics, self.lean, self.linear, self.lanczos = dynamics, lean, linear, lanczos
        self._M = self._diag = self._eig = self._vectors = self._extremes = None
        self._ldlt = self._udut = self._raw = self._equilibrated = None
        self.to_public = to_public
        if matrix is not None:
            self._M = conditioning.check_gim(matrix)

    @property
    def M(self) -> np.ndarray:
        """The mass matrix at q, checked (finite, symmetric, positive diagonal)."""
        if self._M is None:
            if self.linear is not None:
                raise ConditioningError(
                    "this metric needs M itself, which the O(n) path never forms"
                )
            M = (
                gim(self.robot, self.q, data=self.data)
                if self.dynamics is None
                else self.dynamics.gim(self.q)
            )
            self._M = conditioning.check_gim(M)
        return self._M

    @property
    def diag(self) -> np.ndarray:
        """Diag M(q) in Pinocchio's coordinate order, O(n) unless M is formed anyway."""
        if self._diag is None:
            self._diag = (
                np.diag(self.M).copy()
                if self.full or self._M is not None
                else self.to_public(self.linear.diagonal())
                if self.linear is not None
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
        """The spectrum of M, ascending."""
        if self._eig is None:
            self._eig = conditioning.eigenvalues(self.M)
        return self._eig

    @property
    def eigenpairs(self) -> tuple[np.ndarray, np.ndarray]:
        """Eigenvalues as LAPACK returns them (λmin may be ≤ 0 near κ = 1/eps) and vectors.

        One ``eigh``; a positive spectrum then also serves `eigenvalues`.
        """
        if self._vectors is None:
            values, self._vectors = conditioning.eigenpairs(self.M)
            self._raw = values
            if values[0] > 0:  # else `eigenvalues` judges the spectrum itself
                self._eig = values
        return self._raw, self._vectors

    @property
    def extremes(self) -> tuple[float, float]:
        """(λmin, λmax): from the eigen-solve, or by Lanczos on the O(n) products."""
        if self._extremes is None:
            if self.linear is not None:
                from gimwatch.metrics.tracker.extremes import extreme_eigenvalues

                seed, rtol = self.lanczos
                found = extreme_eigenvalues(self.linear, seed=seed, rtol=rtol)
                self._extremes = (found.lambda_min, found.lambda_max)
            else:
                values = self.eigenvalues
                self._extremes = (float(values[0]), float(values[-1]))
        return self._extremes

    @property
    def equilibrated_extremes(self) -> tuple[float, float]:
        """(λmin, λmax) of S = D^-1/2 M D^-1/2: eigen-solve of S, or Lanczos at O(n)."""
        if self._equilibrated is None:
            if self.linear is not None:
                from gimwatch.metrics.tracker.extremes import extreme_eigenvalues

                seed, rtol = self.lanczos
                scaled = equilibrated.ScaledState(self.linear, self.linear.diagonal())
                found = extreme_eigenvalues(scaled, seed=seed, rtol=rtol)
                self._equilibrated = (found.lambda_min, found.lambda_max)
            else:
                self._equilibrated = equilibrated.equilibrated_extremes(self.M)
        return self._equilibrated

    @property
    def ldlt_pivots(self) -> np.ndarray:
        """Pivots of M = L D Lᵀ (elimination from the root), from M's Cholesky factor."""
        if self._ldlt is None:
            self._ldlt = conditioning.ldlt_pivots(self.M)
        return self._ldlt

    @property
    def udut_pivots(self) -> np.ndarray:
        """Pivots of M = U D Uᵀ (elimination from the tips); O(n) on the linear path."""
        if self._udut is None:
            self._udut = (
                self.to_public(self.linear.pivots())
                if self.linear is not None
                else conditioning.udut_pivots(self.M)
            )
        return self._udut


class Metric:
    """One watched quantity. ``full``: needs M (not only its diagonal)."""

    name: ClassVar[str]
    full: ClassVar[bool] = True
    vector: ClassVar[bool] = False

    def __call__(self, state: GimState):
        """The metric's value at the state's configuration."""
        raise NotImplementedError

    def severity(self, value: float) -> float:
        """The value on a condition-number scale (large = ill-conditioned), for alarms."""
        return value


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

    def __init__(self) -> None:
        self.tracker = None

    def __call__(self, state):
        if self.tracker is None:
            self.tracker = equilibrated.equilibrated_tracker(
                state.robot, state.dynamics, state.data, state.lean
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
    TOL: ClassVar[float] = 1e-3

    def __init__(self) -> None:
        self.tracker = None

    def __call__(self, state):
        if self.tracker is None:
            # imported here: the compiled kernels cost a fraction of a second to import,
            # which the dense path (analyze, the watch without this metric) never pays
            from gimwatch.metrics.tracker import KappaTracker, TrackerSettings
            from gimwatch.metrics.tracker.providers import gim_products

            provider = state.lean or gim_products(state.robot, state.dynamics, state.data)
            self.tracker = KappaTracker(provider, state.robot.nv, TrackerSettings(rtol=self.TOL))
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

    def __init__(self) -> None:
        self.tracker = None
        self.products: list[int] = []
        self.fallbacks: list[str] = []
        self.error_estimates: list[float] = []

    def __call__(self, state):
        if self.tracker is None:
            from gimwatch.metrics.tracker import KappaTracker
            from gimwatch.metrics.tracker.providers import gim_products

            robot, dynamics, data = state.robot, state.dynamics, state.data
            provider = state.lean or gim_products(robot, dynamics, data)

            def dense(q: np.ndarray) -> np.ndarray:
                return gim(robot, q, data=data) if dynamics is None else dynamics.gim(q)

            self.tracker = KappaTracker(provider, robot.nv, dense=dense)
        result = self.tracker.sample(state.q)
        self.products.append(result.products)
        self.fallbacks.append(result.fallback)
        self.error_estimates.append(float(result.error_estimate))
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

    def __init__(self) -> None:
        self.servos = None
        self.data = None

    def __call__(self, state):
        # imported here: only a watch of this metric pays for the stability package
        from gimwatch.stability.analysis import DEFAULT_TIMESTEP_S
        from gimwatch.stability.linear_system import LinearSystem, linearise
        from gimwatch.stability.timestep import max_stable_timestep

        robot = state.robot
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
