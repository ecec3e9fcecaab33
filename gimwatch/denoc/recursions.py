"""The DeNOC recursions on a [`BodyTree`][gimwatch.denoc.BodyTree] (internal coordinate order).

Notation of Shah & Saha (2013), Sec. 4, and Saha's DeNOC: body i has the twist
``t_i = [ω_i; v_i]`` at its origin O_i, the twist-propagation matrix
``A_{i,j} = [[1, 0], [−[o_i − o_j]×, 1]]``, the motion-propagation vector p_i
(``[e_i; 0]`` for a revolute joint through O_i, ``[0; e_i]`` for a prismatic one) and the
6×6 mass matrix M_i about O_i; everything is in world axes. Recursions are batched per tree
depth (one numpy call serves every body of a depth), so the only Python loop runs over depths.

Internal coordinates: the root's 6 free-flyer velocities (Pinocchio's order: local linear,
local angular) when floating, then per body 1..N-1 one coordinate, or six for a free joint
(the same local linear and angular velocities of that body, relative to its parent).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gimwatch.denoc.spatial import (
    accumulate,
    body_mass_matrix,
    cross,
    rodrigues,
    shift_mass_matrix,
    shift_twist,
    shift_wrench,
)
from gimwatch.denoc.tree import BALL_KIND, FREE_KIND, BodyTree
from gimwatch.errors import InputError

__all__ = [
    "Kinematics",
    "composite_mass_matrices",
    "forward_dynamics",
    "gim",
    "gim_diagonal",
    "inverse_dynamics",
    "kinematics",
    "udut_pivots_small",
]


@dataclass(frozen=True, eq=False)
class Kinematics:
    """Poses and the DeNOC matrices of every body at one configuration.

    Attributes:
        rotation: Body orientations in the world (N, 3, 3).
        origin: Body origins O_i in the world (N, 3), m.
        offset: ``o_i − o_parent`` (N, 3), zero for the root, m.
        axis: Joint axes e_i in the world (N, 3).
        p: Motion-propagation vectors p_i (N, 6) (the root's row is unused).
        p_root: The root's 6 free-flyer columns (6, 6) (identity-free: [[0, R], [R, 0]]).
        M: Mass matrices M_i about O_i (N, 6, 6), Shah & Saha Eq. 11.
        revolute: Whether each body's joint is revolute/continuous (else prismatic or root).
        prismatic: Whether each body's joint is prismatic.
    """

    rotation: np.ndarray
    origin: np.ndarray
    offset: np.ndarray
    axis: np.ndarray
    p: np.ndarray
    p_root: np.ndarray
    M: np.ndarray
    revolute: np.ndarray
    prismatic: np.ndarray


def _quaternion_matrix(x: float, y: float, z: float, w: float) -> np.ndarray:
    """Rotation of the quaternion (x, y, z, w), assumed unit (Eigen's formula)."""
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
            [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
            [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
        ]
    )


def kinematics(
    tree: BodyTree,
    cos: np.ndarray,
    sin: np.ndarray,
    displacement: np.ndarray,
    root_pose: np.ndarray | None,
    free_pose: np.ndarray | None = None,
) -> Kinematics:
    """Poses, axes, p_i and M_i of all bodies (positions: one batched step per depth).

    Args:
        tree: The body tree.
        cos: cos q_i of revolute/continuous joints (N,), 1 elsewhere.
        sin: sin q_i (N,), 0 elsewhere.
        displacement: q_i of prismatic joints (N,), m, 0 elsewhere.
        root_pose: Free-flyer (x, y, z, qx, qy, qz, qw), or None for a fixed base.
        free_pose: (N, 7): each free joint's (x, y, z, qx, qy, qz, qw) in its row, each ball
            joint's (0, 0, 0, qx, qy, qz, qw) (None: neither).
    """
    n = tree.size
    revolute = (tree.kind == 1) | (tree.kind == 2)
    prismatic = tree.kind == 3
    joint_rotation = tree.placement_rotation @ rodrigues(tree.axis, cos, sin)
    joint_translation = tree.placement_translation + np.einsum(
        "kij,kj->ki", tree.placement_rotation, tree.axis * displacement[:, None]
    )
    free_rows = np.flatnonzero(tree.kind >= FREE_KIND)
    if free_rows.size:  # placement, then the free motion
        if free_pose is None:
            raise InputError("free_pose", "an (N, 7) array: the tree has ball or free joints")
        for i in free_rows:
            joint_rotation[i] = tree.placement_rotation[i] @ _quaternion_matrix(*free_pose[i, 3:7])
            joint_translation[i] += tree.placement_rotation[i] @ free_pose[i, :3]  # ball: 0
    rotation = np.empty((n, 3, 3))
    origin = np.zeros((n, 3))
    if root_pose is None:
        rotation[0] = np.eye(3)
    else:
        origin[0] = root_pose[:3]
        rotation[0] = _quaternion_matrix(*root_pose[3:7])
    for level in tree.levels:
        parent = tree.parent[level]
        rotation[level] = rotation[parent] @ joint_rotation[level]
        origin[level] = origin[parent] + np.einsum(
            "kij,kj->ki", rotation[parent], joint_translation[level]
        )
    offset = np.zeros((n, 3))
    offset[1:] = origin[1:] - origin[tree.parent[1:]]
    axis = np.einsum("kij,kj->ki", rotation, tree.axis)
    p = np.zeros((n, 6))
    p[revolute, :3] = axis[revolute]
    p[prismatic, 3:] = axis[prismatic]
    p_root = np.zeros((6, 6))
    p_root[3:, :3] = rotation[0]
    p_root[:3, 3:] = rotation[0]
    com = np.einsum("kij,kj->ki", rotation, tree.com)
    inertia = rotation @ tree.inertia @ np.swapaxes(rotation, 1, 2)
    M = body_mass_matrix(tree.mass, com, inertia)
    return Kinematics(rotation, origin, offset, axis, p, p_root, M, revolute, prismatic)


def composite_mass_matrices(tree: BodyTree, kin: Kinematics) -> np.ndarray:
    """M̃_i = M_i + Σ_children A_{j,i}ᵀ M̃_j A_{j,i} (Shah & Saha 2013, Eq. 12), from the tips."""
    composite = kin.M.copy()
    for level in reversed(tree.levels):
        shifted = shift_mass_matrix(composite[level], kin.offset[level])
        accumulate(composite, tree.parent[level], shifted)
    return composite


def _free_columns(rotation: np.ndarray) -> np.ndarray:
    """P = [[0, R], [R, 0]] (6, 6): local (v, ω) of a free joint to the world twist [ω; v_O]."""
    columns = np.zeros((6, 6))
    columns[3:, :3] = rotation
    columns[:3, 3:] = rotation
    return columns


def _columns(tree: BodyTree, kin: Kinematics) -> tuple[np.ndarray, np.ndarray]:
    """The motion-propagation columns (nv, 6) and the body each belongs to (nv,).

    One per 1-DoF body, six for the floating root and each free joint, three for each ball
    joint, in body order.
    """
    kind = tree.kind[1:]
    widths = np.where(kind == FREE_KIND, 6, np.where(kind == BALL_KIND, 3, 1))
    body = np.repeat(np.arange(1, tree.size), widths)
    columns = kin.p[body]
    starts = np.cumsum(widths) - widths
    for i in np.flatnonzero(kind == FREE_KIND):
        columns[starts[i] : starts[i] + 6] = _free_columns(kin.rotation[i + 1]).T
    for i in np.flatnonzero(kind == BALL_KIND):  # [R; 0]: the free joint's angular three
        columns[starts[i] : starts[i] + 3] = _free_columns(kin.rotation[i + 1]).T[3:]
    if not tree.floating:
        return columns, body
    return np.vstack([kin.p_root.T, columns]), np.concatenate([np.zeros(6, np.intp), body])


def gim_diagonal(tree: BodyTree, kin: Kinematics) -> np.ndarray:
    """Diagonal of the GIM, ``I_ii = p_iᵀ M̃_i p_i`` (Shah & Saha 2013, Eqs. 11 and 13), O(n)."""
    composite = composite_mass_matrices(tree, kin)
    columns, body = _columns(tree, kin)
    return np.einsum("ki,kij,kj->k", columns, composite[body], columns)


def _ancestry(tree: BodyTree) -> np.ndarray:
    """``anc[i, j]``: body j is body i or one of its ancestors (N, N), one step per depth."""
    anc = np.zeros((tree.size, tree.size), dtype=bool)
    anc[0, 0] = True
    for level in tree.levels:
        anc[level] = anc[tree.parent[level]]
        anc[level, level] = True
    return anc


def gim(tree: BodyTree, kin: Kinematics) -> np.ndarray:
    """The GIM, ``I_ij = p_iᵀ M̃_i A_{i,j} p_j`` for j on the path from i to the root, else 0.

    Shah & Saha (2013), Eq. 11. The product ``(A_{i,j} p_j)ᵀ (M̃_i p_i)`` is formed for all
    pairs at once by moving both to the world origin: the wrench ``M̃_i p_i`` by
    ``A_{i,0}ᵀ`` and the twist p_j by ``A_{0,j}`` (A_{i,j} = A_{i,0} A_{0,j}); entries between
    bodies on different branches are zero.
    """
    composite = composite_mass_matrices(tree, kin)
    columns, body = _columns(tree, kin)
    wrench = np.einsum("kij,kj->ki", composite[body], columns)
    wrench_at_origin = shift_wrench(wrench, kin.origin[body])
    twist_at_origin = shift_twist(columns, -kin.origin[body])
    products = wrench_at_origin @ twist_at_origin.T
    below = _ancestry(tree)[np.ix_(body, body)]
    lower = np.where(below, products, 0.0)
    return lower + lower.T - np.where(below & below.T, products, 0.0)


@dataclass(frozen=True, eq=False)
class _Motion:
    omega: np.ndarray  # (N, 3) angular velocities
    velocity: np.ndarray  # (N, 3) velocities of the origins
    bias: np.ndarray  # (N, 6) c_i: the velocity terms of ṫ_i = A ṫ_parent + p_i q̈_i + c_i


def _motion(tree: BodyTree, kin: Kinematics, qd: np.ndarray, root_v: np.ndarray | None) -> _Motion:
    """Twists ``t_i = A_{i,parent} t_parent + p_i q̇_i`` and the twist-rate bias terms c_i."""
    n = tree.size
    omega, velocity, bias = np.zeros((n, 3)), np.zeros((n, 3)), np.zeros((n, 6))
    if tree.floating:
        if root_v is None:
            raise InputError("root_v", "the free-flyer's twist when the tree is floating")
        omega[0] = kin.rotation[0] @ root_v[3:]
        velocity[0] = kin.rotation[0] @ root_v[:3]
        bias[0, 3:] = cross(omega[0], velocity[0])
    for level in tree.levels:
        parent = tree.parent[level]
        w, r = omega[parent], kin.offset[level]
        axis_rate = kin.axis[level] * qd[level, None]
        rev, pri = kin.revolute[level, None], kin.prismatic[level, None]
        omega[level] = w + rev * axis_rate
        velocity[level] = velocity[parent] + cross(w, r) + pri * axis_rate
        bias[level, :3] = rev * cross(w, axis_rate)
        bias[level, 3:] = cross(w, cross(w, r)) + pri * 2.0 * cross(w, axis_rate)
    return _Motion(omega, velocity, bias)


def _body_bias(tree: BodyTree, kin: Kinematics, motion: _Motion) -> np.ndarray:
    """b_i with ``w_i = M_i ṫ_i + b_i``: ``[ω×I_Cω + d×m ω×(ω×d); m ω×(ω×d)]``."""
    com = np.einsum("kij,kj->ki", kin.rotation, tree.com)
    inertia = kin.rotation @ tree.inertia @ np.swapaxes(kin.rotation, 1, 2)
    w = motion.omega
    centripetal = tree.mass[:, None] * cross(w, cross(w, com))
    gyroscopic = cross(w, np.einsum("kij,kj->ki", inertia, w))
    return np.hstack([gyroscopic + cross(com, centripetal), centripetal])


def _root_rate(gravity: np.ndarray) -> np.ndarray:
    """Twist rate of the world: ``[0; −g]`` (gravity as a fictitious upward acceleration)."""
    return np.concatenate([np.zeros(3), -np.asarray(gravity, dtype=float)])


def inverse_dynamics(
    tree: BodyTree,
    kin: Kinematics,
    qd: np.ndarray,
    qdd: np.ndarray,
    root_v: np.ndarray,
    root_a: np.ndarray,
    gravity: np.ndarray,
) -> np.ndarray:
    """τ = Nᵀ w (Saha's DeNOC inverse dynamics), internal order.

    Twist rates ``ṫ_i = A_{i,parent} ṫ_parent + p_i q̈_i + c_i`` run root to tips, body
    wrenches ``w_i = M_i ṫ_i + b_i``; the wrenches are summed tips to root with ``A_{j,i}ᵀ``
    and ``τ_i = p_iᵀ w̃_i``.
    """
    _one_dof_only(tree)
    motion = _motion(tree, kin, qd, root_v)
    rate = np.zeros((tree.size, 6))
    rate[0] = _root_rate(gravity)
    if tree.floating:
        rate[0] += kin.p_root @ root_a + motion.bias[0]
    for level in tree.levels:
        moved = shift_twist(rate[tree.parent[level]], kin.offset[level])
        rate[level] = moved + kin.p[level] * qdd[level, None] + motion.bias[level]
    wrench = np.einsum("kij,kj->ki", kin.M, rate) + _body_bias(tree, kin, motion)
    for level in reversed(tree.levels):
        accumulate(wrench, tree.parent[level], shift_wrench(wrench[level], kin.offset[level]))
    tau = np.einsum("ki,ki->k", kin.p[1:], wrench[1:])
    if tree.floating:
        tau = np.concatenate([kin.p_root.T @ wrench[0], tau])
    return tau


def _one_dof_only(tree: BodyTree) -> None:
    """The NumPy dynamics below know 1-DoF joints only; free joints run compiled (`.fused`)."""
    if np.any(tree.kind >= FREE_KIND):
        raise NotImplementedError("free and ball joints: use the compiled recursions")


def udut_pivots_small(D: np.ndarray) -> np.ndarray:
    """Pivots of ``D = U Δ Uᵀ`` (U unit upper, elimination from the last coordinate)."""
    work = np.array(D, dtype=float, copy=True)
    pivots = np.empty(len(work))
    for k in range(len(work) - 1, -1, -1):  # 6 steps for the free-flyer block
        pivots[k] = work[k, k]
        work[:k, :k] -= np.outer(work[:k, k], work[:k, k]) / pivots[k]
    return pivots


def forward_dynamics(
    tree: BodyTree,
    kin: Kinematics,
    qd: np.ndarray | None,
    tau: np.ndarray | None,
    root_v: np.ndarray | None,
    gravity: np.ndarray,
) -> tuple[np.ndarray | None, np.ndarray]:
    """Saha's O(n) forward dynamics: the UDUᵀ of the GIM eliminated from the tips.

    Tips to root, each body's articulated mass matrix ``M̂_i = M_i + Σ A_{j,i}ᵀ M̄_j A_{j,i}``
    gives the pivot ``d_i = p_iᵀ M̂_i p_i`` (the D of M = U D Uᵀ) and passes
    ``M̄_i = M̂_i − M̂_i p_i p_iᵀ M̂_i / d_i`` to its parent; the bias wrenches follow the same
    path. Root to tips, ``q̈_i = (φ_i − p_iᵀ M̂_i (A_{i,parent} ṫ_parent + c_i)) / d_i``.

    Returns:
        (q̈ in internal order, or None when ``tau`` is None; the pivots in internal order).
    """
    _one_dof_only(tree)
    articulated = kin.M.copy()
    dynamic = tau is not None
    if tau is not None:
        if qd is None:
            raise InputError("qd", "the joint velocities when tau is given")
        motion = _motion(tree, kin, qd, root_v)
        bias = _body_bias(tree, kin, motion)
        start = 6 if tree.floating else 0
        phi = np.zeros(tree.size)
        phi[1:] = tau[start:]
    pivots = np.ones(tree.size)
    U = np.zeros((tree.size, 6))
    for level in reversed(tree.levels):
        p, r, parent = kin.p[level], kin.offset[level], tree.parent[level]
        U[level] = np.einsum("kij,kj->ki", articulated[level], p)
        d = np.einsum("ki,ki->k", p, U[level])
        pivots[level] = d
        passed = articulated[level] - U[level][:, :, None] * U[level][:, None, :] / d[:, None, None]
        accumulate(articulated, parent, shift_mass_matrix(passed, r))
        if dynamic:
            phi[level] -= np.einsum("ki,ki->k", p, bias[level])
            carried = (
                bias[level]
                + np.einsum("kij,kj->ki", passed, motion.bias[level])
                + U[level] * (phi[level] / d)[:, None]
            )
            accumulate(bias, parent, shift_wrench(carried, r))
    root_D = kin.p_root.T @ articulated[0] @ kin.p_root if tree.floating else None
    body_pivots = pivots[1:]
    if root_D is not None:  # floating
        body_pivots = np.concatenate([udut_pivots_small(root_D), body_pivots])
    if tau is None:
        return None, body_pivots
    rate = np.zeros((tree.size, 6))
    rate[0] = _root_rate(gravity)
    qdd = np.zeros(tree.size)
    root_a = np.zeros(0)
    if root_D is not None:  # floating
        rate[0] += motion.bias[0]
        rhs = tau[:6] - kin.p_root.T @ (bias[0] + articulated[0] @ rate[0])
        root_a = np.linalg.solve(root_D, rhs)
        rate[0] += kin.p_root @ root_a
    for level in tree.levels:
        moved = shift_twist(rate[tree.parent[level]], kin.offset[level]) + motion.bias[level]
        qdd[level] = (phi[level] - np.einsum("ki,ki->k", U[level], moved)) / pivots[level]
        rate[level] = moved + kin.p[level] * qdd[level, None]
    return np.concatenate([root_a, qdd[1:]]), body_pivots
