"""`DenocModel`: the DeNOC GIM and dynamics of a URDF, in Pinocchio's coordinate layout.

Coordinates follow Pinocchio exactly so that matrices and vectors compare entry by entry:
a free-flyer contributes q = (x, y, z, qx, qy, qz, qw) and v = (local linear, local
angular velocity); a continuous joint q = (cos θ, sin θ); revolute and prismatic joints one
number. The joints' order is ``joint_order`` (callers pass Pinocchio's ``model.names[1:]``);
by default the joints sorted by name, ``root_joint`` first.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import numpy.typing as npt

from gimwatch.denoc import recursions
from gimwatch.denoc.chain import chain_body_tree
from gimwatch.denoc.lean import LeanModel, LeanState
from gimwatch.denoc.linear import ConfigurationState, LinearTimeModel
from gimwatch.denoc.tree import BALL_KIND, FREE_FLYER_NAME, FREE_KIND, BodyTree, read_body_tree
from gimwatch.errors import ConditioningError, InputError
from gimwatch.model.chains import ChainSpec

__all__ = ["DenocModel"]

_GRAVITY = (0.0, 0.0, -9.81)


def _vector(name: str, value: npt.ArrayLike, size: int) -> np.ndarray:
    array = np.asarray(value, dtype=float)
    if array.shape != (size,):
        raise InputError(name, f"a vector of {size} numbers", array.shape)
    if not np.all(np.isfinite(array)):
        raise InputError(name, "finite", array.tolist())
    return array


class DenocModel:
    """A robot's body tree and the index maps between its coordinates and DeNOC's.

    Build it with `from_urdf` (or `from_chain`). Internally bodies are numbered
    parents-first; the maps below translate to and from the public (``joint_names``) order.

    The O(n) operations run compiled recursions: the diagonal and inverse and forward
    dynamics those of [`lean`][gimwatch.denoc.DenocModel.lean] (fixed and floating bases), the
    pivots, M·x, M⁻¹·x and the energy those of [`LinearTimeModel`][gimwatch.denoc.LinearTimeModel]
    (fixed base); the dense GIM, the composite mass matrices and floating-base pivots use the
    per-depth NumPy recursions of `.recursions`.
    """

    def __init__(self, tree: BodyTree, joint_order: Sequence[str] | None = None) -> None:
        self.tree = tree
        moving = [name for name in tree.joint_names if name]
        if joint_order is None:
            rest = sorted(name for name in moving if name != FREE_FLYER_NAME)
            joint_order = ([FREE_FLYER_NAME] if tree.floating else []) + rest
        order = tuple(joint_order)
        if sorted(order) != sorted(moving):
            raise InputError(
                "joint_order",
                f"a permutation of the {len(moving)} moving joints of {tree.source}",
                list(order),
                hint=f"expected the names {sorted(moving)}",
            )
        body_of = {name: i for i, name in enumerate(tree.joint_names) if name}
        self._body_of = body_of
        self.joint_names: tuple[str, ...] = order
        self._q_index = np.zeros(tree.size, dtype=np.intp)
        self._root_q = 0
        v_of_body = np.zeros(tree.size, dtype=np.intp)
        nq = nv = 0
        for name in order:
            body = body_of[name]
            if body == 0 or tree.kind[body] == FREE_KIND:  # six DoF: q 7, v 6
                self._q_index[body], v_of_body[body] = nq, nv
                nq, nv = nq + 7, nv + 6
                continue
            if tree.kind[body] == BALL_KIND:  # three rotations: q 4, v 3
                self._q_index[body], v_of_body[body] = nq, nv
                nq, nv = nq + 4, nv + 3
                continue
            self._q_index[body], v_of_body[body] = nq, nv
            nq += 2 if tree.kind[body] == 2 else 1
            nv += 1
        self._root_q = int(self._q_index[0])
        self.nq, self.nv = nq, nv
        self._v_of_body = v_of_body
        #: the free joints below the root (several free bodies, several trees)
        self.free_joints = bool(np.any(tree.kind >= FREE_KIND))
        widths = np.where(tree.kind == FREE_KIND, 6, np.where(tree.kind == BALL_KIND, 3, 1))
        self._widths = widths
        widths[0] = 6 if tree.floating else 0
        #: internal coordinate k is public coordinate _v_index[k]
        self._v_index = np.concatenate(
            [v_of_body[i] + np.arange(widths[i]) for i in range(tree.size)]
        ).astype(np.intp)

    @property
    def dof_names(self) -> tuple[str, ...]:
        """One name per velocity coordinate, public order (``name[k]`` for a joint of six)."""
        if not hasattr(self, "_dof_names"):
            names = [""] * self.nv
            for name in self.joint_names:
                body = self._body_of[name]
                start, width = int(self._v_of_body[body]), int(self._widths[body])
                if width > 1:
                    names[start : start + width] = [f"{name}[{k}]" for k in range(width)]
                else:
                    names[start] = name
            self._dof_names = tuple(names)
        return self._dof_names

    @classmethod
    def from_urdf(
        cls,
        xml_text: str,
        *,
        floating: bool = False,
        source: str = "<string>",
        joint_order: Sequence[str] | None = None,
    ) -> DenocModel:
        """Read URDF text (through yourdfpy, no meshes) into a model.

        Args:
            xml_text: The URDF.
            floating: Put the root link on a free-flyer named ``root_joint``.
            source: Where the text came from, for error messages.
            joint_order: Names of the moving joints in the order the coordinates follow.

        Raises:
            URDFError: Unsupported joint type, not a tree, non-finite numbers, zero axis.
            InputError: ``joint_order`` is not a permutation of the moving joints.
        """
        return cls(read_body_tree(xml_text, floating=floating, source=source), joint_order)

    @classmethod
    def from_chain(cls, spec: ChainSpec) -> DenocModel:
        """The model of a generated rod chain, built from its spec (no URDF text parsed)."""
        return cls(chain_body_tree(spec))

    @property
    def linear(self) -> LinearTimeModel | None:
        """The compiled O(n) model (None with a floating base or free joints)."""
        if self.tree.floating or self.free_joints:
            return None
        if not hasattr(self, "_linear"):
            self._linear = LinearTimeModel(self.tree)
        return self._linear

    def lean(self) -> LeanModel:
        """The same recursions at one compiled call per operation, buffers preallocated.

        Fixed or floating base, Pinocchio's coordinate order, no argument checks (see
        [`LeanModel`][gimwatch.denoc.LeanModel]). Made on first use and kept.
        """
        if not hasattr(self, "_lean"):
            self._lean = LeanModel(self.tree, self._q_index, self._v_of_body, self.nq, self.nv)
        return self._lean

    def state(self, q: npt.ArrayLike) -> ConfigurationState | LeanState:
        """The compiled model's state at ``q``, for repeated O(n) products.

        A fixed-base tree of 1-DoF joints gets the linear-time model's state (one angle per
        body); a floating base or free joints a [`LeanState`][gimwatch.denoc.LeanState] on
        [`lean`][gimwatch.denoc.DenocModel.lean]. Either state's vectors are in internal
        (body) order: use [`to_internal`][gimwatch.denoc.DenocModel.to_internal] and
        [`to_public`][gimwatch.denoc.DenocModel.to_public] to translate.
        """
        q = _vector("q", q, self.nq)
        if self.linear is None:
            return LeanState(self.lean(), q, self._v_index)
        return self._linear_state(self.linear, q)

    def _linear_state(self, linear: LinearTimeModel, q: np.ndarray) -> ConfigurationState:
        """The linear-time model's state at the checked ``q``."""
        first = q[self._q_index[1:]]
        second = q[np.minimum(self._q_index[1:] + 1, self.nq - 1)]
        # continuous joints hold (cos θ, sin θ); the compiled kernels take θ
        angle = np.where(self.tree.kind[1:] == 2, np.arctan2(second, first), first)
        return linear.at(angle)

    def to_internal(self, name: str, x: npt.ArrayLike) -> np.ndarray:
        """A velocity-space vector in public order, checked, in internal (body) order."""
        return _vector(name, x, self.nv)[self._v_index]

    def to_public(self, x: np.ndarray) -> np.ndarray:
        """A velocity-space vector in internal order, in public (``joint_names``) order."""
        out = np.empty(self.nv)
        out[self._v_index] = x
        return out

    def energy(
        self, q: npt.ArrayLike, v: npt.ArrayLike, *, gravity: npt.ArrayLike = _GRAVITY
    ) -> tuple[float, float]:
        """(kinetic ½ vᵀ M v, gravity potential -Σ m_i g·c_i) in J, O(n), any tree."""
        state = self.state(q)
        velocity = self.to_internal("v", v)
        kinetic = 0.5 * float(velocity @ state.matvec(velocity))
        g = _vector("gravity", gravity, 3)
        if self.linear is not None:  # the moving bodies' centres, body 1 on
            return kinetic, -float(self.tree.mass[1:] @ (state.centres_of_mass @ g))
        first = 0 if self.tree.floating else 1  # a fixed root (the world) does not move
        centres = state.centres_of_mass[first:]
        return kinetic, -float(self.tree.mass[first:] @ (centres @ g))

    def permutation_to(self, order: Sequence[str]) -> np.ndarray:
        """Index array ``perm`` (nv,) with ``x_in_order = x[perm]`` for velocity-space vectors.

        ``M[np.ix_(perm, perm)]`` is the GIM with its coordinates in ``order``.
        """
        other = DenocModel(self.tree, order)
        inverse = np.empty(self.nv, dtype=np.intp)
        inverse[other._v_index] = np.arange(self.nv)
        return self._v_index[inverse]

    # -- coordinates -------------------------------------------------------------------
    def _kinematics(self, q: npt.ArrayLike) -> recursions.Kinematics:
        q = _vector("q", q, self.nq)
        tree = self.tree
        first = q[self._q_index]
        second = q[np.minimum(self._q_index + 1, self.nq - 1)]
        kind = tree.kind
        cos = np.where(kind == 1, np.cos(first), np.where(kind == 2, first, 1.0))
        sin = np.where(kind == 1, np.sin(first), np.where(kind == 2, second, 0.0))
        displacement = np.where(kind == 3, first, 0.0)
        root = q[self._root_q : self._root_q + 7] if tree.floating else None
        free = None
        if self.free_joints:
            free = np.zeros((tree.size, 7))
            for i in np.flatnonzero(kind == FREE_KIND):
                free[i] = q[self._q_index[i] : self._q_index[i] + 7]
            for i in np.flatnonzero(kind == BALL_KIND):
                free[i, 3:] = q[self._q_index[i] : self._q_index[i] + 4]
        return recursions.kinematics(tree, cos, sin, displacement, root, free)

    # -- the GIM ----------------------------------------------------------------------
    def gim(self, q: npt.ArrayLike) -> np.ndarray:
        """M(q), (nv, nv), from Shah & Saha (2013) Eqs. 11–13 (composite mass matrices)."""
        M = recursions.gim(self.tree, self._kinematics(q))
        out = np.empty_like(M)
        out[np.ix_(self._v_index, self._v_index)] = M
        return out

    def gim_diagonal(self, q: npt.ArrayLike) -> np.ndarray:
        """Diag M(q) = (p_iᵀ M̃_i p_i) in O(n) (Shah & Saha 2013, Eq. 13)."""
        return self.lean().gim_diagonal(_vector("q", q, self.nq))

    def composite_mass_matrices(self, q: npt.ArrayLike) -> dict[str, np.ndarray]:
        """M̃_i (6×6, ``[ω; v]`` order, about the body origin, world axes) per joint (Eq. 12).

        The root body's is keyed ``root_joint`` when floating (it is the whole robot's).
        """
        composite = recursions.composite_mass_matrices(self.tree, self._kinematics(q))
        start = 0 if self.tree.floating else 1
        names = self.tree.joint_names
        return {names[i]: composite[i] for i in range(start, self.tree.size)}

    # -- dynamics ---------------------------------------------------------------------
    def inverse_dynamics(
        self,
        q: npt.ArrayLike,
        v: npt.ArrayLike,
        a: npt.ArrayLike,
        *,
        gravity: npt.ArrayLike = _GRAVITY,
    ) -> np.ndarray:
        """τ = M(q) a + h(q, v) by the DeNOC recursions (Saha's τ = Nᵀ w), N·m or N."""
        if self.linear is not None:
            tau = self._linear_state(self.linear, _vector("q", q, self.nq)).inverse_dynamics(
                self.to_internal("v", v),
                self.to_internal("a", a),
                gravity=_vector("gravity", gravity, 3),
            )
            return self.to_public(tau)
        return self.lean().inverse_dynamics(
            _vector("q", q, self.nq),
            _vector("v", v, self.nv),
            _vector("a", a, self.nv),
            _vector("gravity", gravity, 3),
        )

    def forward_dynamics(
        self,
        q: npt.ArrayLike,
        v: npt.ArrayLike,
        tau: npt.ArrayLike,
        *,
        gravity: npt.ArrayLike = _GRAVITY,
    ) -> np.ndarray:
        """q̈ = M(q)⁻¹ (τ − h(q, v)) by Saha's O(n) UDUᵀ recursion from the tips (compiled)."""
        arguments = (
            _vector("q", q, self.nq),
            _vector("v", v, self.nv),
            _vector("tau", tau, self.nv),
            _vector("gravity", gravity, 3),
        )
        try:
            return self.lean().forward_dynamics(*arguments)
        except ConditioningError:
            pass  # singular: find and name the coordinate whose pivot vanished
        self._check_pivots(self._internal_pivots(arguments[0]))
        raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")

    def _check_pivots(self, pivots: np.ndarray) -> None:
        """Raise when an elimination pivot is not positive: M(q) is singular there."""
        bad = np.flatnonzero(~(pivots > 0))
        if bad.size:
            k = int(self._v_index[bad[-1]])  # the first eliminated (from the tips)
            raise ConditioningError(
                f"M(q) is singular: the pivot of coordinate {k} ({self._coordinate_name(k)}) "
                f"is {float(pivots[bad[-1]])!r}, so q̈ is undefined (a joint that moves no mass?)"
            )

    def _coordinate_name(self, k: int) -> str:
        """Joint name of public velocity coordinate k (``name[i]`` for a joint of six)."""
        return self.dof_names[k]

    def forward_dynamics_pivots(self, q: npt.ArrayLike) -> np.ndarray:
        """The backward (UDUᵀ) pivots d_i = p_iᵀ M̂_i p_i of the forward-dynamics recursion.

        They are the D of ``M = U D Uᵀ`` for any parents-first coordinate order (Pinocchio's
        ``cholesky.decompose``); the free-flyer's six are the UDUᵀ pivots of its 6×6
        articulated block. A joint that moves no mass has pivot 0 (M(q) is singular); the
        pivots eliminated after it are then NaN.
        """
        return self.to_public(self._internal_pivots(q))

    def _internal_pivots(self, q: npt.ArrayLike) -> np.ndarray:
        if self.linear is not None:
            return self.state(q).pivots()
        if self.free_joints:  # the compiled factor: six UDUᵀ pivots per free joint
            return self.state(q).pivots()
        with np.errstate(divide="ignore", invalid="ignore"):
            _, pivots = recursions.forward_dynamics(
                self.tree, self._kinematics(q), None, None, None, np.zeros(3)
            )
        return pivots
