"""The DeNOC recursions over a tree of 1-DoF joints, compiled with numba.

Conventions (Saha's DeNOC, Shah & Saha 2013 Eqs. 11–13): each body i is described at its
joint origin O_i with world-aligned axes. Twists are t_i = [ω_i; v_Oi] (angular first),
wrenches w_i = [n_Oi; f_i] (moment about O_i first), so that power is t·w.

* joint-motion propagation vector p_i = [e_i; 0] (revolute) or [0; e_i] (prismatic), with
  e_i the joint axis in world axes;
* twist propagation A_ij (from O_j to O_i, r = O_i - O_j): ω_i = ω_j, v_i = v_j + ω_j × r;
* mass matrix of body i about O_i: M_i = [[I_c - m d̃d̃, m d̃], [-m d̃, m 1]], d = c_i - O_i;
* composite mass matrix M̃_j = M_j + Σ_children A_ijᵀ M̃_i A_ij (Eq. 12); M_ii = p_iᵀ M̃_i p_i.

Bodies are in topological order, so a forward loop visits parents first and a backward
loop children first: each recursion is one loop, O(n) time, O(n) memory. Working at O_i
(not at the world origin) keeps lever arms local, which matters for 10^4-link chains.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = [
    "articulated_factor",
    "articulated_solve",
    "body_mass_matrices",
    "composite_diagonal",
    "inverse_dynamics",
    "kinematics",
]


@njit(cache=True)
def _skew(v):
    out = np.zeros((3, 3))
    out[0, 1], out[0, 2] = -v[2], v[1]
    out[1, 0], out[1, 2] = v[2], -v[0]
    out[2, 0], out[2, 1] = -v[1], v[0]
    return out


@njit(cache=True)
def _axis_rotation(axis, angle):
    # Rodrigues' formula for a unit axis.
    k = _skew(axis)
    return np.eye(3) + np.sin(angle) * k + (1.0 - np.cos(angle)) * (k @ k)


@njit(cache=True)
def kinematics(q, parent, joint_type, axis, origin_rotation, origin_position):
    """World orientation R_i, joint origin O_i and world joint axis e_i of every body."""
    n = q.shape[0]
    rotation = np.empty((n, 3, 3))
    origin = np.empty((n, 3))
    e = np.empty((n, 3))
    for i in range(n):
        j = parent[i]
        if j < 0:
            base_r, base_o = np.eye(3), np.zeros(3)
        else:
            base_r, base_o = rotation[j], origin[j]
        frame = base_r @ origin_rotation[i]
        e[i] = frame @ axis[i]
        origin[i] = base_o + base_r @ origin_position[i]
        if joint_type[i] == 0:
            rotation[i] = frame @ _axis_rotation(axis[i], q[i])
        else:
            rotation[i] = frame
            origin[i] = origin[i] + e[i] * q[i]
    return rotation, origin, e


@njit(cache=True)
def body_mass_matrices(rotation, mass, com, inertia):
    """6x6 mass matrix M_i of each body about its joint origin, world axes; and d_i."""
    n = mass.shape[0]
    out = np.zeros((n, 6, 6))
    offset = np.empty((n, 3))
    for i in range(n):
        r = rotation[i]
        d = r @ com[i]
        offset[i] = d
        dt = _skew(d)
        m = mass[i]
        out[i, :3, :3] = r @ inertia[i] @ r.T - m * (dt @ dt)
        out[i, :3, 3:] = m * dt
        out[i, 3:, :3] = -m * dt
        for k in range(3):
            out[i, 3 + k, 3 + k] = m
    return out, offset


@njit(cache=True)
def _shift_congruence(m6, r):
    """A_ijᵀ X A_ij for the twist shift A_ij = [[1, 0], [-r̃, 1]] (r = O_i - O_j)."""
    rt = _skew(r)
    a = m6[:3, :3]
    b = m6[:3, 3:]
    c = m6[3:, :3]
    d = m6[3:, 3:]
    out = np.empty((6, 6))
    # [[1, r̃], [0, 1]] @ [[a, b], [c, d]] @ [[1, 0], [-r̃, 1]]
    top_left = a + rt @ c
    top_right = b + rt @ d
    out[:3, :3] = top_left - top_right @ rt
    out[:3, 3:] = top_right
    out[3:, :3] = c - d @ rt
    out[3:, 3:] = d
    return out


@njit(cache=True)
def _motion_vector(joint_type, e):
    p = np.zeros(6)
    if joint_type == 0:
        p[:3] = e
    else:
        p[3:] = e
    return p


@njit(cache=True)
def composite_diagonal(parent, joint_type, origin, e, body_mass):
    """diag M: p_iᵀ M̃_i p_i with the composite mass matrices of Eq. (12), O(n)."""
    n = parent.shape[0]
    composite = body_mass.copy()
    diag = np.empty(n)
    for i in range(n - 1, -1, -1):
        p = _motion_vector(joint_type[i], e[i])
        diag[i] = p @ composite[i] @ p
        j = parent[i]
        if j >= 0:
            composite[j] += _shift_congruence(composite[i], origin[i] - origin[j])
    return diag


@njit(cache=True)
def inverse_dynamics(parent, joint_type, origin, e, offset, rotation, mass, inertia, qd, qdd,
                     gravity):
    """τ = M(q) q̈ + C(q, q̇) q̇ - g(q): Newton–Euler about the joint origins, O(n).

    Classical accelerations at O_i: ω̇_i = ω̇_j + e_i q̈_i + ω_j × e_i q̇_i (revolute) and
    a_Oi = a_Oj + ω̇_j × r + ω_j × (ω_j × r) (+ e_i q̈_i + 2 ω_j × e_i q̇_i when prismatic).
    """
    n = parent.shape[0]
    omega = np.zeros((n, 3))
    velocity = np.zeros((n, 3))
    alpha = np.zeros((n, 3))
    accel = np.zeros((n, 3))
    force = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    for i in range(n):
        j = parent[i]
        w0, v0, al0, a0 = np.zeros(3), np.zeros(3), np.zeros(3), np.zeros(3)
        r = origin[i].copy()
        if j >= 0:
            w0, v0, al0, a0 = omega[j], velocity[j], alpha[j], accel[j]
            r = origin[i] - origin[j]
        v = v0 + np.cross(w0, r)
        a = a0 + np.cross(al0, r) + np.cross(w0, np.cross(w0, r))
        if joint_type[i] == 0:
            omega[i] = w0 + e[i] * qd[i]
            alpha[i] = al0 + e[i] * qdd[i] + np.cross(w0, e[i]) * qd[i]
        else:
            omega[i] = w0
            alpha[i] = al0
            v = v + e[i] * qd[i]
            a = a + e[i] * qdd[i] + 2.0 * np.cross(w0, e[i]) * qd[i]
        velocity[i] = v
        accel[i] = a
        d = offset[i]
        w = omega[i]
        ic = rotation[i] @ inertia[i] @ rotation[i].T
        a_com = a + np.cross(alpha[i], d) + np.cross(w, np.cross(w, d))
        f = mass[i] * (a_com - gravity)
        force[i] = f
        moment[i] = ic @ alpha[i] + np.cross(w, ic @ w) + np.cross(d, f)
    tau = np.empty(n)
    for i in range(n - 1, -1, -1):
        tau[i] = e[i] @ moment[i] if joint_type[i] == 0 else e[i] @ force[i]
        j = parent[i]
        if j >= 0:
            force[j] += force[i]
            moment[j] += moment[i] + np.cross(origin[i] - origin[j], force[i])
    return tau


@njit(cache=True)
def articulated_factor(parent, joint_type, origin, e, body_mass):
    """The articulated-body (UDUᵀ) factor of M(q), from the tips: U_i, D_i, children's Ia.

    Backward sweep: IA_i = M_i + Σ_children A_ciᵀ Ia_c A_ci, U_i = IA_i p_i, D_i = p_iᵀ U_i,
    Ia_i = IA_i - U_i U_iᵀ / D_i. The D_i are the pivots of M = U D Uᵀ (elimination from the
    tips), i.e. the backward pivots.
    """
    n = parent.shape[0]
    articulated = body_mass.copy()
    u_vectors = np.empty((n, 6))
    pivots = np.empty(n)
    for i in range(n - 1, -1, -1):
        p = _motion_vector(joint_type[i], e[i])
        u = articulated[i] @ p
        dd = p @ u
        u_vectors[i] = u
        pivots[i] = dd
        j = parent[i]
        if j >= 0:
            reduced = articulated[i] - np.outer(u, u) / dd
            articulated[j] += _shift_congruence(reduced, origin[i] - origin[j])
    return u_vectors, pivots


@njit(cache=True)
def articulated_solve(parent, joint_type, origin, e, u_vectors, pivots, tau):
    """x = M⁻¹ τ from the articulated factor: one backward and one forward sweep, O(n)."""
    n = parent.shape[0]
    bias = np.zeros((n, 6))
    rhs = np.empty(n)
    for i in range(n - 1, -1, -1):
        p = _motion_vector(joint_type[i], e[i])
        rhs[i] = tau[i] - p @ bias[i]
        j = parent[i]
        if j >= 0:
            w = bias[i] + u_vectors[i] * (rhs[i] / pivots[i])
            r = origin[i] - origin[j]
            # shift the wrench from O_i to O_j: n_j = n_i + r × f_i
            bias[j, :3] += w[:3] + np.cross(r, w[3:])
            bias[j, 3:] += w[3:]
    x = np.empty(n)
    acc = np.zeros((n, 6))
    for i in range(n):
        j = parent[i]
        a = np.zeros(6)
        if j >= 0:
            r = origin[i] - origin[j]
            a[:3] = acc[j, :3]
            a[3:] = acc[j, 3:] + np.cross(acc[j, :3], r)
        x[i] = (rhs[i] - u_vectors[i] @ a) / pivots[i]
        acc[i] = a + _motion_vector(joint_type[i], e[i]) * x[i]
    return x
