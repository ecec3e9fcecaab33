"""The Python face of the O(n) recursions: a model, its state at q, and matrix-free κ."""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import numpy.typing as npt
from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

from gimwatch.errors import ConditioningError, InputError
from gimwatch.longchain import kernels
from gimwatch.longchain.bodies import Bodies

__all__ = ["ConfigurationState", "LinearTimeModel", "MatrixFreeKappa", "matrix_free_kappa"]

_NO_GRAVITY = np.zeros(3)


class LinearTimeModel:
    """O(n) dynamics of a tree of 1-DoF joints; nothing here grows faster than n.

    Example:
        >>> from gimwatch.chains import chain_spec
        >>> from gimwatch.longchain import LinearTimeModel, bodies_from_chain
        >>> model = LinearTimeModel(bodies_from_chain(chain_spec(4)))
        >>> round(float(model.at([0.0] * 4).diagonal()[0]), 4)
        46.9333
    """

    def __init__(self, bodies: Bodies) -> None:
        self.bodies = bodies

    @property
    def nv(self) -> int:
        """Number of degrees of freedom (= nq: every joint is revolute or prismatic)."""
        return self.bodies.n

    def at(self, q: npt.ArrayLike) -> ConfigurationState:
        """The kinematic state at configuration ``q`` (length nv), with its caches."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nv,) or not np.all(np.isfinite(q)):
            raise InputError("q", f"a finite vector of {self.nv} numbers", q.shape)
        return ConfigurationState(self.bodies, q)

    def forward_dynamics(
        self, q: npt.ArrayLike, v: npt.ArrayLike, tau: npt.ArrayLike, *,
        gravity: npt.ArrayLike = (0.0, 0.0, -9.81),
    ) -> np.ndarray:
        """q̈ = M⁻¹ (τ - C q̇ + g): two O(n) recursions (bias forces, then M⁻¹)."""
        return self.at(q).forward_dynamics(v, tau, gravity=gravity)


class ConfigurationState:
    """Everything at one configuration q: kinematics, body mass matrices, UDUᵀ factor."""

    def __init__(self, bodies: Bodies, q: np.ndarray) -> None:
        self.bodies = bodies
        self.q = q
        self.rotation, self.origin, self.axis_world = kernels.kinematics(
            q, bodies.parent, bodies.joint_type, bodies.axis, bodies.origin_rotation,
            bodies.origin_position_m,
        )
        self.body_mass, self.com_offset = kernels.body_mass_matrices(
            self.rotation, bodies.mass_kg, bodies.com_m, bodies.inertia_kgm2
        )

    def diagonal(self) -> np.ndarray:
        """diag M(q) = p_iᵀ M̃_i p_i (Shah & Saha 2013, Eqs. 11–12), O(n)."""
        b = self.bodies
        return kernels.composite_diagonal(b.parent, b.joint_type, self.origin, self.axis_world,
                                          self.body_mass)

    def inverse_dynamics(self, v: npt.ArrayLike, a: npt.ArrayLike, *,
                         gravity: npt.ArrayLike = (0.0, 0.0, -9.81)) -> np.ndarray:
        """τ = M q̈ + C q̇ - g, O(n) Newton–Euler."""
        b = self.bodies
        return kernels.inverse_dynamics(
            b.parent, b.joint_type, self.origin, self.axis_world, self.com_offset,
            self.rotation, b.mass_kg, b.inertia_kgm2, np.asarray(v, dtype=float),
            np.asarray(a, dtype=float), np.asarray(gravity, dtype=float),
        )

    def matvec(self, x: npt.ArrayLike) -> np.ndarray:
        """M(q) x: inverse dynamics at rest without gravity, O(n)."""
        zeros = np.zeros(self.bodies.n)
        return self.inverse_dynamics(zeros, x, gravity=_NO_GRAVITY)

    @cached_property
    def _factor(self) -> tuple[np.ndarray, np.ndarray]:
        b = self.bodies
        return kernels.articulated_factor(b.parent, b.joint_type, self.origin, self.axis_world,
                                          self.body_mass)

    def pivots(self) -> np.ndarray:
        """The UDUᵀ pivots D_i (elimination from the tips), O(n)."""
        return self._factor[1].copy()

    def solve(self, tau: npt.ArrayLike) -> np.ndarray:
        """M(q)⁻¹ τ by the articulated-body recursion, O(n) (the factor is cached)."""
        b = self.bodies
        u_vectors, pivots = self._factor
        return kernels.articulated_solve(b.parent, b.joint_type, self.origin, self.axis_world,
                                         u_vectors, pivots, np.asarray(tau, dtype=float))

    def forward_dynamics(self, v: npt.ArrayLike, tau: npt.ArrayLike, *,
                         gravity: npt.ArrayLike = (0.0, 0.0, -9.81)) -> np.ndarray:
        """q̈ = M⁻¹ (τ - bias), bias = C q̇ - g from inverse dynamics with q̈ = 0."""
        bias = self.inverse_dynamics(v, np.zeros(self.bodies.n), gravity=gravity)
        return self.solve(np.asarray(tau, dtype=float) - bias)

    def dense(self) -> np.ndarray:
        """The dense M(q), one column per M·e_k: O(n²) — for checks on small n only."""
        n = self.bodies.n
        M = np.column_stack([self.matvec(col) for col in np.eye(n)])
        return (M + M.T) / 2


@dataclass(frozen=True)
class MatrixFreeKappa:
    """κ₂ from extreme eigenvalues found by Lanczos on M and on M⁻¹ (never forming M).

    Attributes:
        kappa: λmax / λmin.
        lambda_max: Largest eigenvalue of M (Lanczos on x ↦ M x).
        lambda_min: Smallest eigenvalue of M (1 / largest of x ↦ M⁻¹ x).
        operator_applications: Number of O(n) recursions applied.
    """

    kappa: float
    lambda_max: float
    lambda_min: float
    operator_applications: int


def matrix_free_kappa(state: ConfigurationState, *, seed: int = 0,
                      rtol: float = 1e-10) -> MatrixFreeKappa:
    """κ₂ of M(q) from its two extreme eigenvalues, with O(n) operators only.

    λmin comes from the largest eigenvalue of M⁻¹ applied by the articulated-body recursion,
    so it keeps its relative accuracy when κ nears 1/eps, where a dense eigensolver (whose
    λmin carries an absolute error of about eps·λmax) no longer resolves it. The start
    vector is random and seeded: a vector of ones is nearly orthogonal to the smallest
    eigenvectors of a straight chain.
    """
    n = state.bodies.n
    if n == 1:
        value = float(state.diagonal()[0])
        return MatrixFreeKappa(1.0, value, value, 1)
    counter = [0]

    def counted(apply):
        def wrapped(x):
            counter[0] += 1
            return apply(np.ravel(x))
        return wrapped

    start = np.random.default_rng(seed).standard_normal(n)
    if n <= 3:  # ARPACK needs k < n - 1: these are cheap enough to form densely
        values = np.linalg.eigvalsh(state.dense())
        return MatrixFreeKappa(float(values[-1] / values[0]), float(values[-1]),
                               float(values[0]), n)
    try:
        lam_max = eigsh(LinearOperator((n, n), matvec=counted(state.matvec), dtype=float), k=1,
                        which="LA", v0=start, tol=rtol, return_eigenvectors=False)[0]
        inv_min = eigsh(LinearOperator((n, n), matvec=counted(state.solve), dtype=float), k=1,
                        which="LA", v0=start, tol=rtol, return_eigenvectors=False)[0]
    except ArpackNoConvergence as exc:
        raise ConditioningError(f"Lanczos did not converge for n = {n} ({exc})") from exc
    if not (lam_max > 0 and inv_min > 0):
        raise ConditioningError("the GIM must be positive definite (Lanczos found λ <= 0)")
    return MatrixFreeKappa(float(lam_max * inv_min), float(lam_max), float(1.0 / inv_min),
                           counter[0])
