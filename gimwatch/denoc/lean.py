"""`LeanModel`: DeNOC's O(n) operations at one compiled call each, with preallocated buffers.

[`DenocModel`][gimwatch.denoc.DenocModel] checks every argument and builds a fresh state per
call; that is right for a cross-check, but in a simulation loop or a watch sampled every
step the checks and the allocations cost more than the recursions (22 µs for one δ sample
of a 20-link chain, 4× a Pinocchio ``aba`` call). A [`LeanModel`][gimwatch.denoc.LeanModel] packs
the tree once and keeps the workspace; each method below is exactly one call into `.fused` and
nothing else, for fixed and floating bases alike, in Pinocchio's coordinate order.

Arguments are NOT checked (shapes, finiteness): the caller owns that, as with Pinocchio's
own Python bindings. Results are written into ``out`` when given (no allocation at all),
else into a new array. The buffers make a LeanModel single-threaded: one per thread.
"""

from __future__ import annotations

import numpy as np

from gimwatch.denoc import fused
from gimwatch.denoc.tree import BodyTree
from gimwatch.errors import ConditioningError

__all__ = ["LeanModel", "LeanState"]

_ZERO_GRAVITY = np.zeros(3)


class LeanModel:
    """The compiled DeNOC recursions of one body tree with their buffers.

    Build it with [`lean`][gimwatch.denoc.DenocModel.lean] (which knows
    the coordinate order).

    Args:
        tree: The body tree.
        q_index: Per body, the index of its first q entry (body 0: the free-flyer's).
        v_index: Per body, the index of its v entry (body 0: the first of the free-flyer's six).
        nq: Length of q.
        nv: Length of v.
    """

    def __init__(
        self, tree: BodyTree, q_index: np.ndarray, v_index: np.ndarray, nq: int, nv: int
    ) -> None:
        n = tree.size
        self.tree, self.nq, self.nv, self.floating = tree, int(nq), int(nv), bool(tree.floating)
        self._index = np.ascontiguousarray(
            np.column_stack(
                [
                    tree.parent,
                    tree.kind,
                    q_index,
                    v_index,
                    np.all(tree.placement_rotation == np.eye(3), axis=(1, 2)),
                ]
            ),
            dtype=np.int64,
        )
        self._geometry = np.ascontiguousarray(
            np.column_stack(
                [
                    tree.axis,
                    tree.placement_rotation.reshape(n, 9),
                    tree.placement_translation,
                    tree.mass,
                    tree.com,
                    tree.inertia.reshape(n, 9),
                ]
            ),
            dtype=float,
        )
        self._rot = np.zeros((n, 3, 3))
        self._vec = np.zeros((n, 5, 3))
        self._six = np.zeros((n, 5, 6))
        self._block = np.zeros((n, 2, 6, 6))
        self._scal = np.ones((n, 2))
        self._root = np.ones((n, 7, 6))  # 6×6 factors: the floating root, free joints
        self._diag = np.empty(self.nv)
        self._comp = np.zeros((n, 10))
        self._configured = False

    def gim_diagonal(self, q: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """Diag M(q) (Shah & Saha 2013, Eqs. 11–13), O(n), one compiled call."""
        out = np.empty(self.nv) if out is None else out
        fused.gim_diagonal(
            q, self._index, self._geometry, self.floating, self._rot, self._vec, self._comp, out
        )
        return out

    def diagonal_ratio(self, q: np.ndarray) -> float:
        """δ = max M_ii / min M_ii (Sec. 4) at q, O(n)."""
        return float(
            fused.gim_diagonal(
                q,
                self._index,
                self._geometry,
                self.floating,
                self._rot,
                self._vec,
                self._comp,
                self._diag,
            )
        )

    def configure(self, q: np.ndarray) -> None:
        """Set the configuration of `gim_product` and `gim_solve` (O(n) factor).

        Raises:
            ConditioningError: M(q) is singular (a pivot is not positive).
        """
        ok = fused.configure(
            q,
            self._index,
            self._geometry,
            self.floating,
            self._rot,
            self._vec,
            self._block,
            self._six,
            self._scal,
            self._root,
        )
        self._configured = bool(ok)
        if not ok:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")

    def factor_pivots(self, q: np.ndarray) -> np.ndarray:
        """The UDUᵀ pivots of M(q) (elimination from the tips), O(n); configures at q.

        One per 1-DoF joint; six for the floating root and each free joint, three for each
        ball joint (the UDUᵀ pivots of its 6×6 or 3×3 articulated system). A pivot ≤ 0
        (M singular) is returned, not raised: the caller names it.
        """
        self._configured = bool(
            fused.configure(q, self._index, self._geometry, self.floating, *self._buffers())
        )
        out = np.empty(self.nv)
        kind, first = self._index[:, 1], self._index[:, 3]
        single = np.flatnonzero(kind[1:] < 4) + 1
        out[first[single]] = self._scal[single, 0]
        several = list(np.flatnonzero(kind[1:] >= 4) + 1) + ([0] if self.floating else [])
        for i in several:
            width = 3 if kind[i] == 5 else 6
            out[first[i] : first[i] + width] = self._root[i, 6, :width]
        return out

    def _buffers(self) -> tuple:
        return self._rot, self._vec, self._block, self._six, self._scal, self._root

    def compiled_operator_arguments(self) -> tuple:
        """The buffers the compiled products read after `configure`.

        `.fused.gim_product` and `.fused.gim_solve` take them after x and before
        out: (index, floating, rot, vec, block, six, scal, root). For compiled callers (the
        κ tracker's Krylov loop) that call the products directly.
        """
        return (
            self._index,
            self.floating,
            self._rot,
            self._vec,
            self._block,
            self._six,
            self._scal,
            self._root,
        )

    def compiled_model_arguments(self) -> tuple:
        """(index, geometry, floating): the packed tree every compiled recursion reads.

        With [`new_workspace`][gimwatch.denoc.LeanModel.new_workspace], for compiled callers that
        keep their own configured state (the κ tracker factors M − σ·1 in its own buffers, leaving
        this model's alone).
        """
        return self._index, self._geometry, self.floating

    def new_workspace(self, *, zeroed: bool = True) -> tuple:
        """Fresh buffers (rot, vec, block, six, scal, root) shaped like this model's own.

        ``zeroed=False`` leaves them uninitialised, for callers whose first call writes
        every entry later read (the kinematics, then the factor).
        """
        make = np.zeros_like if zeroed else np.empty_like
        return tuple(
            make(a) for a in (self._rot, self._vec, self._block, self._six, self._scal, self._root)
        )

    def gim_product(self, x: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """M(q) x at the configured q, O(n)."""
        out = np.empty(self.nv) if out is None else out
        fused.gim_product(
            x, self._index, self.floating, self._rot, self._vec, self._block, self._six, out
        )
        return out

    def gim_solve(self, y: np.ndarray, out: np.ndarray | None = None) -> np.ndarray:
        """M(q)⁻¹ y at the configured q, O(n)."""
        out = np.empty(self.nv) if out is None else out
        fused.gim_solve(
            y,
            self._index,
            self.floating,
            self._rot,
            self._vec,
            self._block,
            self._six,
            self._scal,
            self._root,
            out,
        )
        return out

    def forward_dynamics(
        self,
        q: np.ndarray,
        v: np.ndarray,
        tau: np.ndarray,
        gravity: np.ndarray = _ZERO_GRAVITY,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """q̈ = M(q)⁻¹ (τ − C(q, v) v + g(q)), O(n); leaves the model configured at q.

        Raises:
            ConditioningError: M(q) is singular (a pivot is not positive).
        """
        out = np.empty(self.nv) if out is None else out
        ok = fused.forward_dynamics(
            q,
            v,
            tau,
            gravity,
            self._index,
            self._geometry,
            self.floating,
            self._rot,
            self._vec,
            self._block,
            self._six,
            self._scal,
            self._root,
            out,
        )
        if not ok:
            self._configured = False
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        self._configured = True
        return out

    def inverse_dynamics(
        self,
        q: np.ndarray,
        v: np.ndarray,
        a: np.ndarray,
        gravity: np.ndarray = _ZERO_GRAVITY,
        out: np.ndarray | None = None,
    ) -> np.ndarray:
        """τ = M(q) a + C(q, v) v − g(q), O(n) (Saha's DeNOC inverse dynamics)."""
        out = np.empty(self.nv) if out is None else out
        fused.inverse_dynamics(
            q,
            v,
            a,
            gravity,
            self._index,
            self._geometry,
            self.floating,
            self._rot,
            self._vec,
            self._block,
            self._six,
            out,
        )
        self._configured = False  # the factor is not recomputed by inverse dynamics
        return out


class LeanState:
    """M(q)'s O(n) operators at one configuration, on a [`LeanModel`][gimwatch.denoc.LeanModel].

    What [`ConfigurationState`][gimwatch.denoc.ConfigurationState] gives a fixed-base tree
    of 1-DoF joints — ``diagonal``, ``matvec``, ``solve``, ``pivots`` — for any tree the
    compiled recursions read: a floating base, free joints on any body, several trees.
    Vectors are in the order ``order`` gives (internal coordinate k is the model's
    coordinate ``order[k]``), so that it stands in for the linear-time state.
    The model's buffers hold this configuration: one state per LeanModel at a time.

    Raises:
        ConditioningError: (``solve``) M(q) is singular.
    """

    def __init__(self, model: LeanModel, q: np.ndarray, order: np.ndarray) -> None:
        self.model, self.q, self._order = model, np.ascontiguousarray(q, dtype=float), order
        self._pivots = model.factor_pivots(self.q)

    def _public(self, x: np.ndarray) -> np.ndarray:
        out = np.empty(self.model.nv)
        out[self._order] = x
        return out

    def diagonal(self) -> np.ndarray:
        """Diag M(q), O(n)."""
        return self.model.gim_diagonal(self.q)[self._order]

    def compiled(self) -> tuple[LeanModel, np.ndarray]:
        """(the compiled model, q in its layout): for O(n) work on buffers of its own."""
        return self.model, self.q

    @property
    def centres_of_mass(self) -> np.ndarray:
        """World positions of the bodies' centres of mass (N, 3), m (row 0: the root's)."""
        vec = self.model._vec
        return vec[:, fused.ORIGIN_ROW] + vec[:, fused.COM_OFFSET_ROW]

    def pivots(self) -> np.ndarray:
        """The UDUᵀ pivots (elimination from the tips), O(n)."""
        return self._pivots[self._order]

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """M(q) x, O(n)."""
        return self.model.gim_product(self._public(x))[self._order]

    def solve(self, y: np.ndarray) -> np.ndarray:
        """M(q)⁻¹ y, O(n)."""
        if not self.model._configured:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        return self.model.gim_solve(self._public(y))[self._order]
