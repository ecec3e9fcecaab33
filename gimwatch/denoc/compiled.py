"""The DeNOC recursions over a fixed-base tree of 1-DoF joints, compiled with numba.

These are the O(n)-time, O(n)-memory forms of the recursions in :mod:`.recursions` (which
batch bodies per tree depth in NumPy and also serve floating bases and the dense GIM). Here
each recursion is one compiled loop over the bodies, so a 10^4-link chain costs
milliseconds. Arrays exclude the fixed root: ``parent[i] == -1`` means body i hangs from it;
``joint_type`` is 0 (revolute or continuous, q an angle) or 1 (prismatic).

Conventions (Saha's DeNOC, Shah & Saha 2013 Eqs. 11–13): body i is described at its joint
origin O_i with world-aligned axes. Twists are t_i = [ω_i; v_Oi] (angular first), wrenches
w_i = [n_Oi; f_i] (moment about O_i first), so that power is t·w.

* joint-motion propagation vector p_i = [e_i; 0] (revolute) or [0; e_i] (prismatic), e_i the
  joint axis in world axes;
* twist propagation A_ij from O_j to O_i (r = O_i - O_j): ω_i = ω_j, v_i = v_j + ω_j × r;
* mass matrix of body i about O_i: M_i = [[I_c - m d̃d̃, m d̃], [-m d̃, m 1]], d = c_i - O_i;
* composite mass matrix M̃_j = M_j + Σ_children A_ijᵀ M̃_i A_ij (Eq. 12); M_ii = p_iᵀ M̃_i p_i.

Working at O_i rather than at the world origin keeps lever arms local, which matters for
10^4-link chains. Loops write into preallocated arrays: small temporaries would dominate.
"""

from __future__ import annotations

import numpy as np

from gimwatch.jit import njit

__all__ = [
    "add_shift_congruence",
    "articulated_factor",
    "articulated_solve",
    "body_mass_matrices",
    "composite_diagonal",
    "cross3",
    "inverse_dynamics",
    "kinematics",
]


@njit(cache=True, inline="always")
def cross3(a, b, out):
    """The cross product a × b of 3-vectors, written into out."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


@njit(cache=True)
def kinematics(q, parent, joint_type, axis, origin_rotation, origin_position):
    """World orientation R_i, joint origin O_i, reach r_i = O_i - O_parent, world axis e_i.

    r_i is computed from the joint placement, not as a difference of world positions: for a
    1 µm link 3 m from the origin the difference would keep only ~7 of its 16 digits.
    """
    n = q.shape[0]
    rotation = np.empty((n, 3, 3))
    origin = np.empty((n, 3))
    reach = np.empty((n, 3))
    e = np.empty((n, 3))
    frame = np.empty((3, 3))
    turn = np.empty((3, 3))
    for i in range(n):
        j = parent[i]
        for r in range(3):
            for c in range(3):
                acc = 0.0
                for k in range(3):
                    base = (1.0 if r == k else 0.0) if j < 0 else rotation[j, r, k]
                    acc += base * origin_rotation[i, k, c]
                frame[r, c] = acc
            acc = 0.0
            for k in range(3):
                base = (1.0 if r == k else 0.0) if j < 0 else rotation[j, r, k]
                acc += base * origin_position[i, k]
            reach[i, r] = acc
            origin[i, r] = acc + (0.0 if j < 0 else origin[j, r])
        for r in range(3):
            e[i, r] = frame[r, 0] * axis[i, 0] + frame[r, 1] * axis[i, 1] + frame[r, 2] * axis[i, 2]
        if joint_type[i] == 0:
            # Rodrigues: Rot(a, θ) = 1 + sin θ ã + (1 - cos θ) ã²
            x, y, z = axis[i, 0], axis[i, 1], axis[i, 2]
            s, c1 = np.sin(q[i]), 1.0 - np.cos(q[i])
            turn[0, 0] = 1.0 - c1 * (y * y + z * z)
            turn[1, 1] = 1.0 - c1 * (x * x + z * z)
            turn[2, 2] = 1.0 - c1 * (x * x + y * y)
            turn[0, 1] = -s * z + c1 * x * y
            turn[1, 0] = s * z + c1 * x * y
            turn[0, 2] = s * y + c1 * x * z
            turn[2, 0] = -s * y + c1 * x * z
            turn[1, 2] = -s * x + c1 * y * z
            turn[2, 1] = s * x + c1 * y * z
            for r in range(3):
                for c in range(3):
                    rotation[i, r, c] = (
                        frame[r, 0] * turn[0, c]
                        + frame[r, 1] * turn[1, c]
                        + frame[r, 2] * turn[2, c]
                    )
        else:
            rotation[i] = frame
            for r in range(3):
                origin[i, r] += e[i, r] * q[i]
                reach[i, r] += e[i, r] * q[i]
    return rotation, origin, reach, e


@njit(cache=True)
def body_mass_matrices(rotation, mass, com, inertia):
    """6x6 mass matrix M_i of each body about its joint origin, world axes; and d_i."""
    n = mass.shape[0]
    out = np.zeros((n, 6, 6))
    offset = np.empty((n, 3))
    d = np.empty(3)
    ic = np.empty((3, 3))
    for i in range(n):
        r = rotation[i]
        for a in range(3):
            d[a] = r[a, 0] * com[i, 0] + r[a, 1] * com[i, 1] + r[a, 2] * com[i, 2]
        offset[i] = d
        for a in range(3):  # I_c = R I Rᵀ
            for b in range(3):
                acc = 0.0
                for k in range(3):
                    for m_ in range(3):
                        acc += r[a, k] * inertia[i, k, m_] * r[b, m_]
                ic[a, b] = acc
        m = mass[i]
        dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
        for a in range(3):
            for b in range(3):
                # I_c - m d̃d̃ = I_c + m (|d|² 1 - d dᵀ)
                out[i, a, b] = ic[a, b] + m * ((dd if a == b else 0.0) - d[a] * d[b])
            out[i, 3 + a, 3 + a] = m
        # m d̃ (top right) and -m d̃ (bottom left)
        out[i, 0, 4], out[i, 0, 5] = -m * d[2], m * d[1]
        out[i, 1, 3], out[i, 1, 5] = m * d[2], -m * d[0]
        out[i, 2, 3], out[i, 2, 4] = -m * d[1], m * d[0]
        for a in range(3):
            for b in range(3):
                out[i, 3 + a, b] = out[i, b, 3 + a]
    return out, offset


@njit(cache=True)
def add_shift_congruence(target, x, r, scratch):
    """Target += A_ijᵀ X A_ij, with A_ij = [[1, 0], [-r̃, 1]] (r = O_i - O_j); X symmetric.

    Blockwise, with X = [[a, b], [bᵀ, d]]: the top-right block becomes b + r̃ d, the top-left
    a + r̃ bᵀ - (b + r̃ d) r̃ and the bottom-left its transpose; d is unchanged.
    """
    rx, ry, rz = r[0], r[1], r[2]
    top_right = scratch
    for c in range(3):
        d0, d1, d2 = x[3, 3 + c], x[4, 3 + c], x[5, 3 + c]
        top_right[0, c] = x[0, 3 + c] + (-rz * d1 + ry * d2)
        top_right[1, c] = x[1, 3 + c] + (rz * d0 - rx * d2)
        top_right[2, c] = x[2, 3 + c] + (-ry * d0 + rx * d1)
    for a in range(3):
        # row a of r̃ bᵀ, with bᵀ = x[3:, :3]
        for c in range(3):
            b0, b1, b2 = x[3, c], x[4, c], x[5, c]
            if a == 0:
                rb = -rz * b1 + ry * b2
            elif a == 1:
                rb = rz * b0 - rx * b2
            else:
                rb = -ry * b0 + rx * b1
            # (top_right r̃)[a, c]
            t0, t1, t2 = top_right[a, 0], top_right[a, 1], top_right[a, 2]
            if c == 0:
                tr = t1 * rz - t2 * ry
            elif c == 1:
                tr = -t0 * rz + t2 * rx
            else:
                tr = t0 * ry - t1 * rx
            target[a, c] += x[a, c] + rb - tr
            target[a, 3 + c] += top_right[a, c]
            target[3 + c, a] += top_right[a, c]
            target[3 + a, 3 + c] += x[3 + a, 3 + c]


@njit(cache=True, inline="always")
def _p_dot(joint_type, e, vector6):
    """p_iᵀ x for a 6-vector x (p = [e; 0] or [0; e])."""
    k = 0 if joint_type == 0 else 3
    return e[0] * vector6[k] + e[1] * vector6[k + 1] + e[2] * vector6[k + 2]


@njit(cache=True)
def composite_diagonal(parent, joint_type, reach, e, body_mass):
    """Diag M: p_iᵀ M̃_i p_i with the composite mass matrices of Eq. (12), O(n)."""
    n = parent.shape[0]
    composite = body_mass.copy()
    diag = np.empty(n)
    scratch = np.empty((3, 3))
    column = np.empty(6)
    r = np.empty(3)
    for i in range(n - 1, -1, -1):
        k = 0 if joint_type[i] == 0 else 3
        for a in range(6):
            column[a] = (
                composite[i, a, k] * e[i, 0]
                + composite[i, a, k + 1] * e[i, 1]
                + composite[i, a, k + 2] * e[i, 2]
            )
        diag[i] = _p_dot(joint_type[i], e[i], column)
        j = parent[i]
        if j >= 0:
            for a in range(3):
                r[a] = reach[i, a]
            add_shift_congruence(composite[j], composite[i], r, scratch)
    return diag


@njit(cache=True)
def inverse_dynamics(
    parent, joint_type, reach, e, offset, rotation, mass, inertia, qd, qdd, gravity
):
    """τ = M(q) q̈ + C(q, q̇) q̇ - g(q): Newton–Euler about the joint origins, O(n).

    Classical accelerations at O_i: ω̇_i = ω̇_j + e_i q̈_i + ω_j × e_i q̇_i (revolute) and
    a_Oi = a_Oj + ω̇_j × r + ω_j × (ω_j × r) (+ e_i q̈_i + 2 ω_j × e_i q̇_i when prismatic).
    """
    n = parent.shape[0]
    omega = np.zeros((n, 3))
    alpha = np.zeros((n, 3))
    accel = np.zeros((n, 3))
    force = np.zeros((n, 3))
    moment = np.zeros((n, 3))
    zero = np.zeros(3)
    r = np.empty(3)
    t1 = np.empty(3)
    t2 = np.empty(3)
    a = np.empty(3)
    a_com = np.empty(3)
    ic_alpha = np.empty(3)
    ic_omega = np.empty(3)
    for i in range(n):
        j = parent[i]
        w0, al0, a0 = (zero, zero, zero) if j < 0 else (omega[j], alpha[j], accel[j])
        for k in range(3):
            r[k] = reach[i, k]
        # a = a0 + al0 × r + w0 × (w0 × r)
        cross3(al0, r, t1)
        cross3(w0, r, t2)
        cross3(w0, t2, a)
        for k in range(3):
            a[k] += a0[k] + t1[k]
        cross3(w0, e[i], t1)  # ω_j × e_i
        if joint_type[i] == 0:
            for k in range(3):
                omega[i, k] = w0[k] + e[i, k] * qd[i]
                alpha[i, k] = al0[k] + e[i, k] * qdd[i] + t1[k] * qd[i]
        else:
            for k in range(3):
                omega[i, k] = w0[k]
                alpha[i, k] = al0[k]
                a[k] += e[i, k] * qdd[i] + 2.0 * t1[k] * qd[i]
        accel[i] = a
        d = offset[i]
        w = omega[i]
        # a_com = a + α × d + ω × (ω × d); f = m (a_com - g)
        cross3(alpha[i], d, t1)
        cross3(w, d, t2)
        cross3(w, t2, a_com)
        for k in range(3):
            force[i, k] = mass[i] * (a_com[k] + a[k] + t1[k] - gravity[k])
        # I_c = R I Rᵀ applied without forming it: I_c x = R (I (Rᵀ x))
        rot = rotation[i]
        for k in range(3):
            t1[k] = rot[0, k] * alpha[i, 0] + rot[1, k] * alpha[i, 1] + rot[2, k] * alpha[i, 2]
            t2[k] = rot[0, k] * w[0] + rot[1, k] * w[1] + rot[2, k] * w[2]
        for k in range(3):
            ic_alpha[k] = 0.0
            ic_omega[k] = 0.0
            for m in range(3):
                local_a = (
                    inertia[i, 0, m] * t1[0] + inertia[i, 1, m] * t1[1] + inertia[i, 2, m] * t1[2]
                )
                local_w = (
                    inertia[i, 0, m] * t2[0] + inertia[i, 1, m] * t2[1] + inertia[i, 2, m] * t2[2]
                )
                ic_alpha[k] += rot[k, m] * local_a
                ic_omega[k] += rot[k, m] * local_w
        # n_O = I_c α + ω × I_c ω + d × f
        cross3(w, ic_omega, t1)
        cross3(d, force[i], t2)
        for k in range(3):
            moment[i, k] = ic_alpha[k] + t1[k] + t2[k]
    tau = np.empty(n)
    for i in range(n - 1, -1, -1):
        source = moment[i] if joint_type[i] == 0 else force[i]
        tau[i] = e[i, 0] * source[0] + e[i, 1] * source[1] + e[i, 2] * source[2]
        j = parent[i]
        if j >= 0:
            for k in range(3):
                r[k] = reach[i, k]
            cross3(r, force[i], t1)
            for k in range(3):
                force[j, k] += force[i, k]
                moment[j, k] += moment[i, k] + t1[k]
    return tau


@njit(cache=True, error_model="numpy")  # a zero pivot (singular M) gives inf/nan, not an error
def articulated_factor(parent, joint_type, reach, e, body_mass):
    """The articulated-body (UDUᵀ) factor of M(q), from the tips: U_i = IA_i p_i, D_i, Ia_i.

    Backward sweep: IA_i = M_i + Σ_children A_ciᵀ Ia_c A_ci, U_i = IA_i p_i, D_i = p_iᵀ U_i,
    Ia_i = IA_i - U_i U_iᵀ / D_i. The D_i are the pivots of M = U D Uᵀ (elimination from the
    tips), i.e. the backward pivots; the Ia_i are kept for the bias forces of
    :func:`articulated_solve`.
    """
    n = parent.shape[0]
    articulated = body_mass.copy()
    u_vectors = np.empty((n, 6))
    pivots = np.empty(n)
    scratch = np.empty((3, 3))
    r = np.empty(3)
    for i in range(n - 1, -1, -1):
        k = 0 if joint_type[i] == 0 else 3
        for a in range(6):
            u_vectors[i, a] = (
                articulated[i, a, k] * e[i, 0]
                + articulated[i, a, k + 1] * e[i, 1]
                + articulated[i, a, k + 2] * e[i, 2]
            )
        pivot = _p_dot(joint_type[i], e[i], u_vectors[i])
        pivots[i] = pivot
        j = parent[i]
        if j >= 0:
            for a in range(6):
                for b in range(6):
                    articulated[i, a, b] -= u_vectors[i, a] * u_vectors[i, b] / pivot
            for a in range(3):
                r[a] = reach[i, a]
            add_shift_congruence(articulated[j], articulated[i], r, scratch)
    return u_vectors, pivots, articulated


@njit(cache=True, error_model="numpy")
def articulated_solve(
    parent,
    joint_type,
    reach,
    e,
    offset,
    rotation,
    mass,
    inertia,
    u_vectors,
    pivots,
    articulated,
    qd,
    tau,
    gravity,
):
    """q̈ = M⁻¹ (τ - C q̇ + g) by the articulated-body algorithm on the cached factor, O(n).

    Gravity enters as an upward acceleration -g of the fixed base, and the velocity terms
    as the bias acceleration c_i and bias wrench b_i of each body, so that q̈ comes out of
    the recursion without the large joint torques of gravity ever being formed and then
    cancelled (forming them and solving M q̈ = τ - h would lose digits in proportion to κ):

    * forward: ω_i; c_i = [ω_j × e_i q̇_i; ω_j × (ω_j × r)] (revolute) or
      [0; ω_j × (ω_j × r) + 2 ω_j × e_i q̇_i] (prismatic); b_i = [ω × I_c ω + d × f_b; f_b],
      f_b = m ω × (ω × d);
    * backward: pA_i = b_i + Σ A_ciᵀ pa_c, u_i = τ_i - p_iᵀ pA_i,
      pa_i = pA_i + Ia_i c_i + U_i u_i / D_i;
    * forward: a'_i = A_ij a_j + c_i, q̈_i = (u_i - U_iᵀ a'_i) / D_i, a_i = a'_i + p_i q̈_i.

    With q̇ = 0 and g = 0 it is x = M⁻¹ τ (the operator of the matrix-free κ).
    """
    n = parent.shape[0]
    omega = np.zeros((n, 3))
    bias_acc = np.zeros((n, 6))
    bias = np.zeros((n, 6))
    zero = np.zeros(3)
    r = np.empty(3)
    t1 = np.empty(3)
    t2 = np.empty(3)
    local = np.empty(3)
    moving = False
    for i in range(n):
        if qd[i] != 0.0:
            moving = True
            break
    if moving:
        for i in range(n):
            j = parent[i]
            w0 = zero if j < 0 else omega[j]
            for k in range(3):
                r[k] = reach[i, k]
            cross3(w0, r, t1)
            cross3(w0, t1, t2)  # ω_j × (ω_j × r)
            cross3(w0, e[i], t1)  # ω_j × e_i
            for k in range(3):
                bias_acc[i, 3 + k] = t2[k]
                if joint_type[i] == 0:
                    omega[i, k] = w0[k] + e[i, k] * qd[i]
                    bias_acc[i, k] = t1[k] * qd[i]
                else:
                    omega[i, k] = w0[k]
                    bias_acc[i, 3 + k] += 2.0 * t1[k] * qd[i]
            # b_i: f_b = m ω × (ω × d), n_b = ω × I_c ω + d × f_b
            w = omega[i]
            d = offset[i]
            cross3(w, d, t1)
            cross3(w, t1, t2)
            for k in range(3):
                bias[i, 3 + k] = mass[i] * t2[k]
            rot = rotation[i]
            for k in range(3):
                t1[k] = rot[0, k] * w[0] + rot[1, k] * w[1] + rot[2, k] * w[2]
            for k in range(3):
                local[k] = (
                    inertia[i, k, 0] * t1[0] + inertia[i, k, 1] * t1[1] + inertia[i, k, 2] * t1[2]
                )
            for k in range(3):
                t1[k] = rot[k, 0] * local[0] + rot[k, 1] * local[1] + rot[k, 2] * local[2]
            cross3(w, t1, t2)
            cross3(d, bias[i, 3:], t1)
            for k in range(3):
                bias[i, k] = t2[k] + t1[k]
    rhs = np.empty(n)
    wrench = np.empty(6)
    for i in range(n - 1, -1, -1):
        rhs[i] = tau[i] - _p_dot(joint_type[i], e[i], bias[i])
        j = parent[i]
        if j >= 0:
            scale = rhs[i] / pivots[i]
            for a in range(6):
                acc = bias[i, a] + u_vectors[i, a] * scale
                if moving:
                    for b in range(6):
                        acc += articulated[i, a, b] * bias_acc[i, b]
                wrench[a] = acc
            # shift the wrench from O_i to O_j: n_j += n + r × f
            rx = reach[i, 0]
            ry = reach[i, 1]
            rz = reach[i, 2]
            bias[j, 0] += wrench[0] + ry * wrench[5] - rz * wrench[4]
            bias[j, 1] += wrench[1] + rz * wrench[3] - rx * wrench[5]
            bias[j, 2] += wrench[2] + rx * wrench[4] - ry * wrench[3]
            bias[j, 3] += wrench[3]
            bias[j, 4] += wrench[4]
            bias[j, 5] += wrench[5]
    x = np.empty(n)
    acc6 = np.zeros((n, 6))
    a = np.zeros(6)
    for i in range(n):
        j = parent[i]
        if j >= 0:
            # shift the parent's acceleration from O_j to O_i: a_Oi = a_Oj + α_j × r
            for k in range(3):
                a[k] = acc6[j, k]
                t1[k] = reach[i, k]
            a[3] = acc6[j, 3] + acc6[j, 1] * t1[2] - acc6[j, 2] * t1[1]
            a[4] = acc6[j, 4] + acc6[j, 2] * t1[0] - acc6[j, 0] * t1[2]
            a[5] = acc6[j, 5] + acc6[j, 0] * t1[1] - acc6[j, 1] * t1[0]
        else:
            # the fixed base accelerates upwards at -g: gravity without gravity forces
            for k in range(3):
                a[k] = 0.0
                a[3 + k] = -gravity[k]
        for k in range(6):
            a[k] += bias_acc[i, k]
        dot = 0.0
        for k in range(6):
            dot += u_vectors[i, k] * a[k]
        x[i] = (rhs[i] - dot) / pivots[i]
        acc6[i] = a
        kk = 0 if joint_type[i] == 0 else 3
        for k in range(3):
            acc6[i, kk + k] += e[i, k] * x[i]
    return x
