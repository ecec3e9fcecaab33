"""O(n) dynamics of fixed-base trees without forming M, one angle per body, on DeNOC's kernels.

[`LinearTimeModel`][gimwatch.denoc.LinearTimeModel] wraps a fixed-base
[`BodyTree`][gimwatch.denoc.BodyTree]; [`LinearTimeModel.at`][gimwatch.denoc.LinearTimeModel.at]
gives the [`ConfigurationState`][gimwatch.denoc.ConfigurationState] at one configuration with diag
M, M·x, M⁻¹·x, the UDUᵀ pivots, inverse and forward dynamics, each O(n) in time and memory.
κ₂ from these operators is the metrics layer's
([`extreme_eigenvalues`][gimwatch.metrics.tracker.extremes.extreme_eigenvalues], on the κ
tracker's Krylov engine).

Coordinates are the tree's body order (parents first), one per body: an angle for revolute
and continuous joints, a displacement for prismatic ones. Pinocchio's Data for an n-joint
model needs memory growing as n³, and the dense GIM n²; nothing here grows faster than n.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import numpy.typing as npt

from gimwatch.denoc import fused
from gimwatch.denoc.lean import LeanModel
from gimwatch.denoc.tree import BodyTree
from gimwatch.errors import ConditioningError, InputError

__all__ = ["ConfigurationState", "LinearTimeModel"]

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

    def compiled(self) -> tuple[LeanModel, np.ndarray]:
        """(the compiled model, q in its layout): for O(n) work on buffers of its own.

        The κ tracker factors M − σ·1 there (shift-invert, Sylvester's inertia), which the
        products of this state do not offer.
        """
        return self.model.kernels, self.q

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
