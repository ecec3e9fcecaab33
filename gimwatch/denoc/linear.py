"""O(n) dynamics of fixed-base trees without forming M, one angle per body, on DeNOC's kernels.

[`LinearTimeModel`][gimwatch.denoc.LinearTimeModel] wraps a fixed-base
[`BodyTree`][gimwatch.denoc.BodyTree]; [`LinearTimeModel.at`][gimwatch.denoc.LinearTimeModel.at]
gives the [`ConfigurationState`][gimwatch.denoc.ConfigurationState] at one configuration with diag
M, M·x, M⁻¹·x, the UDUᵀ pivots, inverse and forward dynamics, each O(n) in time and memory.
[`extreme_eigenvalues`][gimwatch.denoc.extreme_eigenvalues] turns M·x and M⁻¹·x into κ₂ by Lanczos.

Coordinates are the tree's body order (parents first), one per body: an angle for revolute
and continuous joints, a displacement for prismatic ones. Pinocchio's Data for an n-joint
model needs memory growing as n³, and the dense GIM n²; nothing here grows faster than n.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np
import numpy.typing as npt
import scipy.linalg

from gimwatch.denoc import fused
from gimwatch.denoc.lean import LeanModel
from gimwatch.denoc.tree import BodyTree
from gimwatch.errors import ConditioningError, InputError

__all__ = ["ConfigurationState", "LinearTimeModel", "MatrixFreeKappa", "extreme_eigenvalues"]

_REVOLUTE, _CONTINUOUS = 1, 2


class LinearTimeModel:
    """O(n) dynamics of a fixed-base tree of 1-DoF joints.

    The recursions are DeNOC's compiled kernels (`.fused`, the same that serve
    [`LeanModel`][gimwatch.denoc.LeanModel]); this class gives them one coordinate per body,
    an angle for revolute and continuous joints, and a state object per configuration.

    Examples:
        >>> from gimwatch.model.chains import chain_spec
        >>> from gimwatch.denoc import LinearTimeModel, chain_body_tree
        >>> model = LinearTimeModel(chain_body_tree(chain_spec(4)))
        >>> round(float(model.at([0.0] * 4).diagonal()[0]), 4)
        46.9333
    """

    def __init__(self, tree: BodyTree) -> None:
        if tree.floating:
            raise InputError(
                "the body tree",
                "fixed-base for the O(n) compiled path",
                "a floating base",
                hint="use DenocModel for floating bases",
            )
        self.tree = tree
        # One coordinate per moving body, in body order: q[i - 1] and v[i - 1] for body i.
        # Continuous joints take an angle here, so the kernels read them as revolute.
        as_angles = replace(tree, kind=np.where(tree.kind == _CONTINUOUS, _REVOLUTE, tree.kind))
        index = np.arange(-1, tree.size - 1)
        index[0] = 0
        self.kernels = LeanModel(as_angles, index, index, tree.size - 1, tree.size - 1)

    @property
    def nv(self) -> int:
        """Number of coordinates (one per moving body)."""
        return self.tree.size - 1

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Joint names in coordinate (body) order."""
        return self.tree.joint_names[1:]

    def at(self, q: npt.ArrayLike) -> ConfigurationState:
        """The state at ``q`` (angles / displacements in body order), with its caches."""
        q = np.asarray(q, dtype=float)
        if q.shape != (self.nv,):
            raise InputError("q", f"a vector of {self.nv} numbers", q.shape)
        if not np.all(np.isfinite(q)):
            raise InputError("q", "finite", "NaN or inf entries")
        return ConfigurationState(self, q)


class ConfigurationState:
    """Kinematics and body mass matrices at one q, and the operators built on them.

    Each state owns its workspace (O(n) buffers), so states at several configurations can
    be used side by side.
    """

    def __init__(self, model: LinearTimeModel, q: np.ndarray) -> None:
        self.model = model
        self.q = np.ascontiguousarray(q, dtype=float)
        self._index, self._geometry, _ = model.kernels.compiled_model_arguments()
        # Every entry the kernels read is written first (checked with NaN-filled buffers),
        # so the O(n) workspace is not zeroed: at 10^4 links that is most of a state's cost.
        self._rot, self._vec, self._block, self._six, self._scal, self._root = (
            model.kernels.new_workspace(zeroed=False)
        )
        fused.kinematics(
            self.q, self._index, self._geometry, False, self._rot, self._vec, self._block
        )
        self._factored = False

    def diagonal(self) -> np.ndarray:
        """Diag M(q) = p_iᵀ M̃_i p_i (Shah & Saha 2013, Eqs. 11–12), O(n)."""
        out = np.empty(self.model.nv)
        composite = np.empty((self.model.tree.size, 10))  # written before it is read
        # gim_diagonal recomputes the poses at self.q: the same values, in the same buffers
        fused.gim_diagonal(
            self.q, self._index, self._geometry, False, self._rot, self._vec, composite, out
        )
        return out

    def inverse_dynamics(
        self, v: npt.ArrayLike, a: npt.ArrayLike, *, gravity: npt.ArrayLike = (0.0, 0.0, -9.81)
    ) -> np.ndarray:
        """τ = M(q) a + C(q, v) v - g(q), O(n) Newton–Euler about the joint origins."""
        out = np.empty(self.model.nv)
        # Kinematics recomputed in place (same q, same values); the factor is left alone.
        fused.inverse_dynamics(
            self.q,
            np.ascontiguousarray(v, dtype=float),
            np.ascontiguousarray(a, dtype=float),
            np.ascontiguousarray(gravity, dtype=float),
            self._index,
            self._geometry,
            False,
            self._rot,
            self._vec,
            self._block,
            self._six,
            out,
        )
        return out

    def matvec(self, x: npt.ArrayLike) -> np.ndarray:
        """M(q) x: Newton–Euler from rest without gravity, O(n)."""
        out = np.empty(self.model.nv)
        fused.gim_product(
            np.ascontiguousarray(x, dtype=float),
            self._index,
            False,
            self._rot,
            self._vec,
            self._block,
            self._six,
            out,
        )
        return out

    @property
    def centres_of_mass(self) -> np.ndarray:
        """World positions of the moving bodies' centres of mass (nv, 3), m."""
        return self._vec[1:, fused.ORIGIN_ROW] + self._vec[1:, fused.COM_OFFSET_ROW]

    def _workspace(self) -> tuple:
        return self._rot, self._vec, self._block, self._six, self._scal, self._root

    def _factor(self) -> None:
        """The articulated-body factor (UDUᵀ from the tips), computed once per state."""
        if not self._factored:
            fused.factor_shifted(0.0, self._index, False, *self._workspace())
            self._factored = True

    def pivots(self) -> np.ndarray:
        """The UDUᵀ pivots D_i (elimination from the tips; the backward pivots), O(n)."""
        self._factor()
        return self._scal[1:, 0].copy()

    def solve(self, tau: npt.ArrayLike) -> np.ndarray:
        """M(q)⁻¹ τ by the articulated-body recursion, O(n); the factor is cached."""
        self._require_positive_pivots()
        out = np.empty(self.model.nv)
        fused.gim_solve(
            np.ascontiguousarray(tau, dtype=float), self._index, False, *self._workspace(), out
        )
        return out

    def _require_positive_pivots(self) -> None:
        self._factor()
        pivots = self._scal[1:, 0]
        if not np.all(pivots > 0):
            k = int(np.flatnonzero(~(pivots > 0))[-1])
            raise ConditioningError(
                f"M(q) is singular: the pivot of {self.model.joint_names[k]} is {pivots[k]!r} "
                "(a joint that moves no mass?)"
            )

    def forward_dynamics(
        self, v: npt.ArrayLike, tau: npt.ArrayLike, *, gravity: npt.ArrayLike = (0.0, 0.0, -9.81)
    ) -> np.ndarray:
        """q̈ = M⁻¹ (τ - C v + g) by the articulated-body algorithm, O(n); the factor is cached."""
        self._require_positive_pivots()
        out = np.empty(self.model.nv)
        fused.forward_dynamics_factored(
            np.ascontiguousarray(v, dtype=float),
            np.ascontiguousarray(tau, dtype=float),
            np.ascontiguousarray(gravity, dtype=float),
            self._index,
            self._geometry,
            False,
            *self._workspace(),
            out,
        )
        return out

    def dense(self) -> np.ndarray:
        """The dense M(q), one column per M·e_k: O(n²) work — for checks on small n."""
        n = self.model.nv
        M = np.column_stack([self.matvec(column) for column in np.eye(n)])
        return (M + M.T) / 2


@dataclass(frozen=True)
class MatrixFreeKappa:
    """κ₂ of M(q) from Lanczos on x ↦ M x and x ↦ M⁻¹ x (M never formed).

    The one record of every matrix-free κ in gimwatch: DeNOC's plain Lanczos
    ([`extreme_eigenvalues`][gimwatch.denoc.extreme_eigenvalues]) and ARPACK on Pinocchio's RNEA/ABA
    ([`kappa_matrix_free`][gimwatch.metrics.matrix_free.kappa_matrix_free]). Ritz values approach
    the extreme eigenvalues from inside the spectrum, so ``lambda_max`` and ``1 / lambda_min``
    are lower bounds and ``kappa`` a lower bound of κ₂ that converges to it.

    Attributes:
        kappa: λmax / λmin.
        lambda_max: Largest eigenvalue of M.
        lambda_min: Smallest eigenvalue of M (1 / the largest of M⁻¹).
        products: O(n) products applied (M·x and M⁻¹·x together).
        last_relative_change: Relative change of the Ritz values over the last 10 steps
            (below ``rtol`` when converged; larger when ``max_steps`` ran out); NaN when
            ARPACK, which checks its own residuals, found them.
        vector_max: Eigenvector of λmax, to warm-start a nearby sample (None if not kept).
        vector_min: Eigenvector of λmin (None if not kept).
    """

    kappa: float
    lambda_max: float
    lambda_min: float
    products: int
    last_relative_change: float = float("nan")
    vector_max: np.ndarray | None = field(default=None, repr=False)
    vector_min: np.ndarray | None = field(default=None, repr=False)


def _largest_ritz_value(apply, start: np.ndarray, *, rtol: float, max_steps: int):
    """Largest eigenvalue of a symmetric operator by plain Lanczos, O(n) memory.

    No restarts: the smallest eigenvalues of a long chain's M are clustered (relative gaps
    ~1/n²), where restarted ARPACK (``eigsh``) needs 10^4–10^5 products at n = 10^4 while
    the largest Ritz value itself settles in a few hundred steps. No reorthogonalisation
    either: losing orthogonality only adds spurious copies of converged Ritz values, never
    moves the extreme one, and keeping the basis would cost O(n·steps) memory. Stops when
    the largest Ritz value changes by less than ``rtol`` (relative) over 10 steps.

    Returns:
        (Ritz value, steps taken, its relative change over the last 10 steps).
    """
    v = start / np.linalg.norm(start)
    v_previous = np.zeros_like(v)
    alphas: list[float] = []
    betas: list[float] = []
    beta = 0.0
    previous = np.nan
    steps = min(max_steps, start.size)
    for k in range(steps):
        w = apply(v) - beta * v_previous
        alpha = float(w @ v)
        w -= alpha * v
        alphas.append(alpha)
        beta = float(np.linalg.norm(w))
        exhausted = beta <= 1e-14 * max(abs(a) for a in alphas) or k == steps - 1
        if k % 10 == 9 or exhausted:
            theta = scipy.linalg.eigh_tridiagonal(
                np.array(alphas),
                np.array(betas),
                eigvals_only=True,
                select="i",
                select_range=(k, k),
            )[0]
            change = abs(theta - previous) / abs(theta)
            if exhausted or change <= rtol:
                return float(theta), k + 1, float(change) if k >= 10 else 0.0
            previous = theta
        betas.append(beta)
        v_previous, v = v, w / beta
    raise AssertionError("unreachable")  # the loop returns at its last step


def extreme_eigenvalues(
    state: ConfigurationState, *, seed: int = 0, rtol: float = 1e-10, max_steps: int = 3000
) -> MatrixFreeKappa:
    """κ₂ of M(q) from its extreme eigenvalues with O(n) operators only.

    λmin comes from the largest eigenvalue of M⁻¹ applied by the articulated-body
    recursion, so it keeps its relative accuracy when κ nears 1/eps, where a dense
    eigensolver (λmin with an absolute error of about eps·λmax) no longer resolves it. The
    start vector is random and seeded: a vector of ones is nearly orthogonal to the smallest
    eigenvectors of a straight chain.

    Args:
        state: The configuration state.
        seed: Seed of the random start vector.
        rtol: Relative change of the Ritz values at which Lanczos stops.
        max_steps: Lanczos steps per eigenvalue at most.
    """
    start = np.random.default_rng(seed).standard_normal(state.model.nv)
    lam_max, steps_max, change_max = _largest_ritz_value(
        state.matvec, start, rtol=rtol, max_steps=max_steps
    )
    inv_min, steps_min, change_min = _largest_ritz_value(
        state.solve, start, rtol=rtol, max_steps=max_steps
    )
    if not (lam_max > 0 and inv_min > 0):
        raise ConditioningError("the GIM must be positive definite (Lanczos found λ <= 0)")
    return MatrixFreeKappa(
        kappa=float(lam_max * inv_min),
        lambda_max=float(lam_max),
        lambda_min=float(1.0 / inv_min),
        products=steps_max + steps_min,
        last_relative_change=max(change_max, change_min),
    )
