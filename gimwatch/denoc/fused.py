"""The DeNOC recursions fused into one compiled call each, fixed or floating base, no allocation.

DeNOC's one compiled implementation (numba); `.recursions` is the NumPy reference,
written equation by equation. Every public operation — diag M(q), M·x, M⁻¹·y, forward and
inverse dynamics — is ONE compiled call that reads q, v, τ in the caller's coordinate order
(given per body by ``index``), writes into caller-owned buffers and returns, so that a Python
caller pays one dispatch per operation and nothing else. Two wrappers own the buffers:
[`gimwatch.denoc.lean.LeanModel`][gimwatch.denoc.LeanModel] (Pinocchio's coordinates, fixed or
floating base) and [`gimwatch.denoc.linear.LinearTimeModel`][gimwatch.denoc.LinearTimeModel] (one
angle per body, fixed base, for 10^4–10^5 links, with a state object per configuration).

Arrays cover the whole tree, root included (body 0). With a fixed base body 0 is the world:
its acceleration is ``[0; −g]`` (gravity as an upward acceleration of the base) and nothing is
passed to it. With a floating base body 0 moves on Pinocchio's free-flyer: q = (x, y, z, qx,
qy, qz, qw), v = (local linear, local angular), and its six columns are
``P = [[0, R], [R, 0]]`` (local ``[v; ω]`` to the world twist ``[ω; v_O]``). A free joint
(kind 4) on any other body is the same six columns with that body's R: several free bodies
and several trees (children of a fixed body 0, the world) are ordinary trees here. Such a body
passes its parent the articulated inertia IA − U S⁻¹ Uᵀ (U = IA P, S = Pᵀ IA P − shift·1;
zero when shift = 0) and keeps the 6×6 factor of S in ``root[i]``.

Packed inputs (built once by [`LeanModel`][gimwatch.denoc.LeanModel]):

* ``index`` (N, 5) int64: parent, joint kind (0 root, 1 revolute, 2 continuous, 3 prismatic,
  4 free: six DoF of the body relative to its parent, Pinocchio's free-flyer, 5 ball: its
  three rotations, q a quaternion (x, y, z, w), v the angular velocity in the body frame),
  index of the body's first q entry, index of its v entry (root, free, ball: of the first),
  1 when the joint's placement rotation is the identity (its product is skipped);
* ``geometry`` (N, 28): axis (0:3), placement rotation row-major (3:12), placement translation
  (12:15), mass (15), centre of mass (16:19), inertia about it row-major (19:28).

Buffers: ``rot`` (N, 3, 3); ``vec`` (N, 5, 3) = origin, reach r_i = O_i − O_parent, world axis
e_i, centre-of-mass offset d_i, angular velocity ω_i; ``six`` (N, 5, 6) = U_i, velocity bias
c_i, bias wrench b_i, twist rate, wrench; ``block`` (N, 2, 6, 6) = M_i, composite /
articulated M̃_i; ``scal`` (N, 2) = pivot D_i, u_i; ``root`` (N, 7, 6) = the 6×6 UDUᵀ factor
(rows 0–5 U, row 6 D) of the floating root (``root[0]``) and of each free joint's body;
``comp`` (N, 10) = the composite mass, first moment and rotational inertia the diagonal
needs. Conventions and equations as in `.recursions` (Shah & Saha 2013, Eqs. 11–13; Saha's
DeNOC; Featherstone's articulated-body algorithm).
"""

from __future__ import annotations

import numpy as np

from gimwatch.jit import njit

__all__ = [
    "COM_OFFSET_ROW",
    "ORIGIN_ROW",
    "configure",
    "factor_shifted",
    "forward_dynamics",
    "forward_dynamics_factored",
    "gim_diagonal",
    "gim_product",
    "gim_solve",
    "inverse_dynamics",
    "kinematics",
]

_ORIGIN, _REACH, _AXIS, _COM, _OMEGA = 0, 1, 2, 3, 4
#: Rows of the ``vec`` buffer that callers read after the kinematics: origins O_i and the
#: centre-of-mass offsets d_i = c_i − O_i, both in world axes (m).
ORIGIN_ROW, COM_OFFSET_ROW = _ORIGIN, _COM
_U, _C, _B, _RATE, _WRENCH = 0, 1, 2, 3, 4


@njit(cache=True, inline="always")
def cross3(a, b, out):
    """The cross product a × b of 3-vectors, written into out."""
    out[0] = a[1] * b[2] - a[2] * b[1]
    out[1] = a[2] * b[0] - a[0] * b[2]
    out[2] = a[0] * b[1] - a[1] * b[0]


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


@njit(cache=True)
def _root_columns(rotation, out):
    """P = [[0, R], [R, 0]]: the free-flyer's local (v, ω) to the world twist [ω; v_O]."""
    out[:] = 0.0
    for r in range(3):
        for c in range(3):
            out[r, 3 + c] = rotation[r, c]
            out[3 + r, c] = rotation[r, c]


@njit(cache=True, inline="always")
def _quaternion_matrix(x, y, z, w, out):
    """The rotation of the unit quaternion (x, y, z, w) into out (Eigen's formula)."""
    out[0, 0], out[0, 1], out[0, 2] = (
        1 - 2 * (y * y + z * z),
        2 * (x * y - z * w),
        2 * (x * z + y * w),
    )
    out[1, 0], out[1, 1], out[1, 2] = (
        2 * (x * y + z * w),
        1 - 2 * (x * x + z * z),
        2 * (y * z - x * w),
    )
    out[2, 0], out[2, 1], out[2, 2] = (
        2 * (x * z - y * w),
        2 * (y * z + x * w),
        1 - 2 * (x * x + y * y),
    )


@njit(cache=True, inline="always")
def _width(kind):
    """Velocity coordinates of a free (kind 4: six) or ball (kind 5: three) joint."""
    return 3 if kind == 5 else 6


@njit(cache=True)  # not inlined: the 1-DoF loops stay small
def _add_free_twist(kind, rotation, x, k, out):
    """Out += P x[k:k+w]: free P = [[0, R], [R, 0]] (local (v, ω)), ball P = [R; 0] (local ω).

    Local velocities to the world twist [ω; v_O].
    """
    if kind == 5:
        for a in range(3):
            out[a] += rotation[a, 0] * x[k] + rotation[a, 1] * x[k + 1] + rotation[a, 2] * x[k + 2]
        return
    for a in range(3):
        out[a] += rotation[a, 0] * x[k + 3] + rotation[a, 1] * x[k + 4] + rotation[a, 2] * x[k + 5]
        out[3 + a] += rotation[a, 0] * x[k] + rotation[a, 1] * x[k + 1] + rotation[a, 2] * x[k + 2]


@njit(cache=True)  # not inlined: the 1-DoF loops stay small
def _free_load(kind, rotation, w, out):
    """Out = Pᵀ w: the wrench [n; f] as the joint's generalized forces (Rᵀ f, Rᵀ n; ball: Rᵀ n)."""
    if kind == 5:
        for a in range(3):
            out[a] = rotation[0, a] * w[0] + rotation[1, a] * w[1] + rotation[2, a] * w[2]
        return
    for a in range(3):
        out[a] = rotation[0, a] * w[3] + rotation[1, a] * w[4] + rotation[2, a] * w[5]
        out[3 + a] = rotation[0, a] * w[0] + rotation[1, a] * w[1] + rotation[2, a] * w[2]


@njit(cache=True)
def _poses(q, index, geometry, floating, rot, vec):
    """Body orientations R_i, origins O_i, reaches r_i = O_i − O_parent, world axes e_i."""
    n = index.shape[0]
    frame = np.empty((3, 3))
    turn = np.empty((3, 3))
    for a in range(3):
        for b in range(3):
            rot[0, a, b] = 1.0 if a == b else 0.0
        vec[0, _ORIGIN, a] = 0.0
        vec[0, _REACH, a] = 0.0
        vec[0, _AXIS, a] = 0.0
    if floating:
        k = index[0, 2]
        _quaternion_matrix(q[k + 3], q[k + 4], q[k + 5], q[k + 6], rot[0])
        for a in range(3):
            vec[0, _ORIGIN, a] = q[k + a]
    for i in range(1, n):
        j, kind, k = index[i, 0], index[i, 1], index[i, 2]
        g = geometry[i]
        for r in range(3):
            for c in range(3):
                if index[i, 4]:  # the joint frame is its parent's, turned by nothing
                    frame[r, c] = rot[j, r, c]
                else:
                    frame[r, c] = (
                        rot[j, r, 0] * g[3 + c] + rot[j, r, 1] * g[6 + c] + rot[j, r, 2] * g[9 + c]
                    )
            vec[i, _REACH, r] = rot[j, r, 0] * g[12] + rot[j, r, 1] * g[13] + rot[j, r, 2] * g[14]
        for r in range(3):
            vec[i, _AXIS, r] = frame[r, 0] * g[0] + frame[r, 1] * g[1] + frame[r, 2] * g[2]
        if kind == 3:
            rot[i] = frame
            for r in range(3):
                vec[i, _REACH, r] += vec[i, _AXIS, r] * q[k]
        elif kind >= 4:  # free: (x, y, z) in the joint frame, then the quaternion's turn
            kq = k + 3 if kind == 4 else k  # ball: the quaternion alone
            _quaternion_matrix(q[kq], q[kq + 1], q[kq + 2], q[kq + 3], turn)
            for r in range(3):
                vec[i, _AXIS, r] = 0.0
                if kind == 4:
                    vec[i, _REACH, r] += (
                        frame[r, 0] * q[k] + frame[r, 1] * q[k + 1] + frame[r, 2] * q[k + 2]
                    )
                for cc in range(3):
                    rot[i, r, cc] = (
                        frame[r, 0] * turn[0, cc]
                        + frame[r, 1] * turn[1, cc]
                        + frame[r, 2] * turn[2, cc]
                    )
        else:
            if kind == 1:
                s, c = np.sin(q[k]), np.cos(q[k])
            else:  # continuous: q holds (cos θ, sin θ)
                c, s = q[k], q[k + 1]
            c1 = 1.0 - c
            x, y, z = g[0], g[1], g[2]
            # Rodrigues: Rot(a, θ) = 1 + sin θ ã + (1 - cos θ) ã²
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
                for cc in range(3):
                    rot[i, r, cc] = (
                        frame[r, 0] * turn[0, cc]
                        + frame[r, 1] * turn[1, cc]
                        + frame[r, 2] * turn[2, cc]
                    )
        for r in range(3):
            vec[i, _ORIGIN, r] = vec[j, _ORIGIN, r] + vec[i, _REACH, r]


@njit(cache=True)
def _kinematics(q, index, geometry, floating, rot, vec, block):
    """Poses, reaches, world axes and body mass matrices M_i about O_i (world axes)."""
    _poses(q, index, geometry, floating, rot, vec)
    n = index.shape[0]
    ic = np.empty((3, 3))
    rim = np.empty((3, 3))
    for i in range(0 if floating else 1, n):
        g = geometry[i]
        r = rot[i]
        for a in range(3):
            vec[i, _COM, a] = r[a, 0] * g[16] + r[a, 1] * g[17] + r[a, 2] * g[18]
        for a in range(3):  # T = R I, then I_c = T Rᵀ (symmetric: upper half, mirrored)
            for mm in range(3):
                rim[a, mm] = r[a, 0] * g[19 + mm] + r[a, 1] * g[22 + mm] + r[a, 2] * g[25 + mm]
        for a in range(3):
            for b in range(a, 3):
                acc = rim[a, 0] * r[b, 0] + rim[a, 1] * r[b, 1] + rim[a, 2] * r[b, 2]
                ic[a, b] = acc
                ic[b, a] = acc
        m = g[15]
        d = vec[i, _COM]
        dd = d[0] * d[0] + d[1] * d[1] + d[2] * d[2]
        out = block[i, 0]
        out[:] = 0.0
        for a in range(3):
            for b in range(3):
                out[a, b] = ic[a, b] + m * ((dd if a == b else 0.0) - d[a] * d[b])
            out[3 + a, 3 + a] = m
        out[0, 4], out[0, 5] = -m * d[2], m * d[1]
        out[1, 3], out[1, 5] = m * d[2], -m * d[0]
        out[2, 3], out[2, 4] = -m * d[1], m * d[0]
        for a in range(3):
            for b in range(3):
                out[3 + a, b] = out[b, 3 + a]


@njit(cache=True, inline="always")
def _p_dot(kind, e, vector6):
    """p_iᵀ x for a 6-vector x."""
    k = 3 if kind == 3 else 0
    return e[0] * vector6[k] + e[1] * vector6[k + 1] + e[2] * vector6[k + 2]


@njit(cache=True, inline="always")
def _shift_rate(parent_rate, r, out):
    """Out = A parent_rate: [α; a_O] moved by r (a_O' = a_O + α × r)."""
    out[0], out[1], out[2] = parent_rate[0], parent_rate[1], parent_rate[2]
    out[3] = parent_rate[3] + parent_rate[1] * r[2] - parent_rate[2] * r[1]
    out[4] = parent_rate[4] + parent_rate[2] * r[0] - parent_rate[0] * r[2]
    out[5] = parent_rate[5] + parent_rate[0] * r[1] - parent_rate[1] * r[0]


@njit(cache=True, inline="always")
def _add_shifted_wrench(target, w, r):
    """Target += Aᵀ w: the wrench [n; f] at O + r added at O (n' = n + r × f)."""
    target[0] += w[0] + r[1] * w[5] - r[2] * w[4]
    target[1] += w[1] + r[2] * w[3] - r[0] * w[5]
    target[2] += w[2] + r[0] * w[4] - r[1] * w[3]
    target[3] += w[3]
    target[4] += w[4]
    target[5] += w[5]


@njit(cache=True)
def _root_system(rotation, articulated, columns, out, kind=4):
    """Pᵀ X P (w×w) for a free (6×6) or ball joint's (3×3) columns P."""
    _root_columns(rotation, columns)
    if kind == 5:  # [R; 0]: the free-flyer's angular columns, moved first
        for r in range(6):
            for c in range(3):
                columns[r, c] = columns[r, 3 + c]
    w = _width(kind)
    for a in range(w):
        for b in range(w):
            acc = 0.0
            for r in range(6):
                if columns[r, a] != 0.0:
                    for s in range(6):
                        acc += columns[r, a] * articulated[r, s] * columns[s, b]
            out[a, b] = acc


@njit(cache=True)
def _udut6(matrix, root, w=6):
    """UDUᵀ of a w×w (elimination from the last coordinate) into root[:w] (U), root[6] (D)."""
    work = matrix.copy()
    for k in range(w - 1, -1, -1):
        pivot = work[k, k]
        root[6, k] = pivot
        for i in range(w):
            root[i, k] = 0.0 if i > k else (1.0 if i == k else work[i, k] / pivot)
        for a in range(k):
            for b in range(k):
                work[a, b] -= work[a, k] * work[b, k] / pivot


@njit(cache=True)
def _solve6(root, rhs, out, w=6):
    """Out = (U D Uᵀ)⁻¹ rhs with the w×w factor of `_udut6`."""
    z = np.empty(6)
    for i in range(w - 1, -1, -1):
        acc = rhs[i]
        for k in range(i + 1, w):
            acc -= root[i, k] * z[k]
        z[i] = acc
    for i in range(w):
        acc = z[i] / root[6, i]
        for k in range(i):
            acc -= root[k, i] * out[k]
        out[i] = acc


@njit(cache=True)
def _factor_free(kind, art, rotation, shift, factor, passed):
    """A free (ball) joint's 6×6 (3×3) system S = Pᵀ IA P − shift·1 factored (UDUᵀ).

    Writes into ``passed`` what its parent receives, IA − U S⁻¹ Uᵀ with U = IA P (zero for
    a free joint when shift = 0, as its P is invertible). Returns whether S's pivots are
    positive.
    """
    width = _width(kind)
    system = np.empty((6, 6))
    columns = np.empty((6, 6))
    _root_system(rotation, art, columns, system, kind)
    for k in range(width):
        system[k, k] -= shift
    _udut6(system, factor, width)
    ok = True
    for k in range(width):
        ok = ok and factor[6, k] > 0.0
    u = np.empty((6, 6))  # U = IA P
    for a in range(6):
        for b in range(width):
            acc = 0.0
            for r in range(6):
                acc += art[a, r] * columns[r, b]
            u[a, b] = acc
    w = np.empty(6)
    for b in range(6):  # column b of S⁻¹ Uᵀ is S⁻¹ (row b of U)
        _solve6(factor, u[b], w, width)
        for a in range(6):
            acc = 0.0
            for k in range(width):
                acc += u[a, k] * w[k]
            passed[a, b] = art[a, b] - acc
    return ok


@njit(cache=True, error_model="numpy")
def _factor(index, floating, rot, vec, block, six, scal, root, shift):
    """Articulated-body factor of M − shift·1 from the tips: U_i = IA_i p_i, D_i = p_iᵀ U_i − shift.

    The shift enters the pivots as a (negative) armature would: D_i = p_iᵀ IA_i p_i − shift,
    IA_i − U_i U_iᵀ / D_i passed on; with a floating base the free-flyer's 6×6 system
    Pᵀ IA_0 P − shift·1 is factored too (UDUᵀ), and so is each free joint's (`_factor_free`).
    The factor is a congruence of M − shift·1 (Featherstone's LTDL), so by Sylvester's law of
    inertia every pivot is positive exactly when shift < λmin(M). Returns whether every pivot
    is positive.
    """
    n = index.shape[0]
    for i in range(0 if floating else 1, n):
        block[i, 1] = block[i, 0]
    scratch = np.empty((3, 3))
    passed = np.empty((6, 6))
    ok = True
    for i in range(n - 1, 0, -1):
        kind = index[i, 1]
        j = index[i, 0]
        if kind >= 4:  # IA_i stays in block[i, 1] for the articulated pass
            ok = _factor_free(kind, block[i, 1], rot[i], shift, root[i], passed) and ok
            scal[i, 0] = 1.0
            if j > 0 or floating:
                add_shift_congruence(block[j, 1], passed, vec[i, _REACH], scratch)
            continue
        e = vec[i, _AXIS]
        k = 3 if kind == 3 else 0
        art = block[i, 1]
        u = six[i, _U]
        for a in range(6):
            u[a] = art[a, k] * e[0] + art[a, k + 1] * e[1] + art[a, k + 2] * e[2]
        pivot = _p_dot(kind, e, u) - shift
        scal[i, 0] = pivot
        ok = ok and pivot > 0.0
        if j > 0 or floating:
            for a in range(6):
                for b in range(6):
                    art[a, b] -= u[a] * u[b] / pivot
            add_shift_congruence(block[j, 1], art, vec[i, _REACH], scratch)
    if floating:
        system = np.empty((6, 6))
        columns = np.empty((6, 6))
        _root_system(rot[0], block[0, 1], columns, system)
        for k in range(6):
            system[k, k] -= shift
        _udut6(system, root[0])
        for k in range(6):
            ok = ok and root[0, 6, k] > 0.0
    return ok


@njit(cache=True)
def _velocity_terms(v, index, geometry, floating, rot, vec, six):
    """ω_i, the twist-rate bias c_i and the bias wrench b_i of every body; False when v = 0.

    c_i = [ω_j × e_i q̇_i; ω_j × (ω_j × r_i)] (revolute) or [0; ω_j × (ω_j × r_i) +
    2 ω_j × e_i q̇_i] (prismatic); the free-flyer's c_0 = [0; ω_0 × v_0]; b_i = [ω × I_c ω +
    d × f_b; f_b] with f_b = m ω × (ω × d).
    """
    n = index.shape[0]
    moving = False
    for k in range(v.shape[0]):
        if v[k] != 0.0:
            moving = True
            break
    if not moving:
        return False
    t1 = np.empty(3)
    t2 = np.empty(3)
    local = np.empty(3)
    for a in range(3):
        vec[0, _OMEGA, a] = 0.0
    for a in range(6):
        six[0, _C, a] = 0.0
    if floating:
        k = index[0, 3]
        r0 = rot[0]
        for a in range(3):
            vec[0, _OMEGA, a] = r0[a, 0] * v[k + 3] + r0[a, 1] * v[k + 4] + r0[a, 2] * v[k + 5]
            t2[a] = r0[a, 0] * v[k] + r0[a, 1] * v[k + 1] + r0[a, 2] * v[k + 2]
        cross3(vec[0, _OMEGA], t2, t1)
        for a in range(3):
            six[0, _C, 3 + a] = t1[a]
    rel_w = np.empty(3)
    rel_v = np.empty(3)
    for i in range(1, n):
        j, kind = index[i, 0], index[i, 1]
        w0 = vec[j, _OMEGA]
        cross3(w0, vec[i, _REACH], t1)
        cross3(w0, t1, t2)  # ω_j × (ω_j × r)
        c = six[i, _C]
        if kind >= 4:
            # relative twist P v: ω_rel = R ω_l, v_rel = R v_l (ball: 0); c = [ω_j × ω_rel;
            # ω_j × (ω_j × r) + (ω_j + ω_i) × v_rel] (d/dt of R x is ω_i × R x + R ẋ)
            k, r_i = index[i, 3], rot[i]
            kw = k + 3 if kind == 4 else k
            for a in range(3):
                rel_v[a] = (
                    r_i[a, 0] * v[k] + r_i[a, 1] * v[k + 1] + r_i[a, 2] * v[k + 2]
                    if kind == 4
                    else 0.0
                )
                rel_w[a] = r_i[a, 0] * v[kw] + r_i[a, 1] * v[kw + 1] + r_i[a, 2] * v[kw + 2]
                vec[i, _OMEGA, a] = w0[a] + rel_w[a]
            cross3(w0, rel_w, t1)
            for a in range(3):
                c[a] = t1[a]
                c[3 + a] = t2[a]
                local[a] = w0[a] + vec[i, _OMEGA, a]
            cross3(local, rel_v, t1)
            for a in range(3):
                c[3 + a] += t1[a]
            continue
        qd = v[index[i, 3]]
        e = vec[i, _AXIS]
        cross3(w0, e, t1)  # ω_j × e_i
        for a in range(3):
            c[3 + a] = t2[a]
            if kind == 3:
                vec[i, _OMEGA, a] = w0[a]
                c[a] = 0.0
                c[3 + a] += 2.0 * t1[a] * qd
            else:
                vec[i, _OMEGA, a] = w0[a] + e[a] * qd
                c[a] = t1[a] * qd
    for i in range(0 if floating else 1, n):
        g = geometry[i]
        w = vec[i, _OMEGA]
        d = vec[i, _COM]
        b = six[i, _B]
        cross3(w, d, t1)
        cross3(w, t1, t2)
        for a in range(3):
            b[3 + a] = g[15] * t2[a]
        r = rot[i]
        for a in range(3):
            t1[a] = r[0, a] * w[0] + r[1, a] * w[1] + r[2, a] * w[2]
        for a in range(3):
            local[a] = g[19 + 3 * a] * t1[0] + g[20 + 3 * a] * t1[1] + g[21 + 3 * a] * t1[2]
        for a in range(3):
            t1[a] = r[a, 0] * local[0] + r[a, 1] * local[1] + r[a, 2] * local[2]
        cross3(w, t1, t2)
        cross3(d, b[3:], t1)
        for a in range(3):
            b[a] = t2[a] + t1[a]
    return True


@njit(cache=True, error_model="numpy")
def _free_bias_up(i, kind, passes, tau, moving, index, rot, vec, block, six, root):
    """A free or ball joint's body in `_articulated_pass` from the tips: u, and its parent's share.

    Keeps u = τ_i − Pᵀ pA_i in its U row; passes pA + IA (c + P z), z = S⁻¹ (u − Pᵀ IA c).
    """
    load = np.empty(6)
    wrench = np.empty(6)
    z = np.empty(6)
    k, width = index[i, 3], _width(kind)
    u6 = six[i, _U]
    _free_load(kind, rot[i], six[i, _WRENCH], load)
    for a in range(width):
        u6[a] = tau[k + a] - load[a]
    if not passes:
        return
    art = block[i, 1]
    for a in range(6):  # IA c, then u − Pᵀ IA c
        acc = 0.0
        if moving:
            for b in range(6):
                acc += art[a, b] * six[i, _C, b]
        wrench[a] = acc
    _free_load(kind, rot[i], wrench, load)
    for a in range(width):
        load[a] = u6[a] - load[a]
    _solve6(root[i], load, z, width)
    for a in range(6):  # c + P z
        wrench[a] = six[i, _C, a] if moving else 0.0
    _add_free_twist(kind, rot[i], z, 0, wrench)
    for a in range(6):
        acc = six[i, _WRENCH, a]
        for b in range(6):
            acc += art[a, b] * wrench[b]
        load[a] = acc
    _add_shifted_wrench(six[index[i, 0], _WRENCH], load, vec[i, _REACH])


@njit(cache=True, error_model="numpy")
def _free_acceleration(i, kind, index, rot, block, six, root, rate, out):
    """A free or ball joint's q̈ = S⁻¹ (u − Pᵀ IA ṫ) from the root, and its body's ṫ += P q̈."""
    load = np.empty(6)
    wrench = np.empty(6)
    z = np.empty(6)
    art, width = block[i, 1], _width(kind)
    for a in range(6):  # IA ṫ
        acc = 0.0
        for b in range(6):
            acc += art[a, b] * rate[b]
        wrench[a] = acc
    _free_load(kind, rot[i], wrench, load)
    for a in range(width):
        load[a] = six[i, _U, a] - load[a]
    k = index[i, 3]
    _solve6(root[i], load, z, width)
    for a in range(width):
        out[k + a] = z[a]
    _add_free_twist(kind, rot[i], z, 0, rate)


@njit(cache=True, error_model="numpy")
def _articulated_pass(tau, gravity, moving, floating, index, rot, vec, block, six, scal, root, out):
    """q̈ = M⁻¹ (τ − C q̇ + g) on the factor: bias wrenches from the tips, q̈ from the root.

    A free joint's body keeps u = τ_i − Pᵀ pA_i (in its U row) and passes
    pA + IA (c + P z), z = S⁻¹ (u − Pᵀ IA c); from the root its q̈ is S⁻¹ (u − Pᵀ IA ṫ)
    with ṫ the twist rate its parent moves it by.
    """
    n = index.shape[0]
    wrench = np.empty(6)
    for i in range(n):
        for a in range(6):
            six[i, _WRENCH, a] = six[i, _B, a] if moving else 0.0
    for i in range(n - 1, 0, -1):
        kind = index[i, 1]
        j = index[i, 0]
        if kind >= 4:
            _free_bias_up(
                i, kind, j > 0 or floating, tau, moving, index, rot, vec, block, six, root
            )
            continue
        u = tau[index[i, 3]] - _p_dot(kind, vec[i, _AXIS], six[i, _WRENCH])
        scal[i, 1] = u
        if j > 0 or floating:
            scale = u / scal[i, 0]
            for a in range(6):
                acc = six[i, _WRENCH, a] + six[i, _U, a] * scale
                if moving:
                    for b in range(6):
                        acc += block[i, 1, a, b] * six[i, _C, b]
                wrench[a] = acc
            _add_shifted_wrench(six[j, _WRENCH], wrench, vec[i, _REACH])
    rate0 = six[0, _RATE]
    for a in range(3):
        rate0[a] = 0.0
        rate0[3 + a] = -gravity[a]
    if floating:
        k = index[0, 3]
        if moving:
            for a in range(6):
                rate0[a] += six[0, _C, a]
        columns = np.empty((6, 6))
        _root_columns(rot[0], columns)
        rhs = np.empty(6)
        for a in range(6):  # IA_0 rate0 + pA_0
            acc = six[0, _WRENCH, a]
            for b in range(6):
                acc += block[0, 1, a, b] * rate0[b]
            wrench[a] = acc
        for a in range(6):
            acc = tau[k + a]
            for r in range(6):
                acc -= columns[r, a] * wrench[r]
            rhs[a] = acc
        accel = np.empty(6)
        _solve6(root[0], rhs, accel)
        for a in range(6):
            out[k + a] = accel[a]
            for b in range(6):
                rate0[a] += columns[a, b] * accel[b]
    for i in range(1, n):
        j, kind = index[i, 0], index[i, 1]
        rate = six[i, _RATE]
        _shift_rate(six[j, _RATE], vec[i, _REACH], rate)
        if moving:
            for a in range(6):
                rate[a] += six[i, _C, a]
        if kind >= 4:
            _free_acceleration(i, kind, index, rot, block, six, root, rate, out)
            continue
        dot = 0.0
        for a in range(6):
            dot += six[i, _U, a] * rate[a]
        x = (scal[i, 1] - dot) / scal[i, 0]
        out[index[i, 3]] = x
        kk = 3 if kind == 3 else 0
        e = vec[i, _AXIS]
        for a in range(3):
            rate[kk + a] += e[a] * x


@njit(cache=True)
def _newton_euler_pass(acc, gravity, moving, floating, index, rot, vec, block, six, out):
    """τ = M q̈ + C q̇ − g: twist rates from the root, wrenches w_i = M_i ṫ_i + b_i summed back."""
    n = index.shape[0]
    rate0 = six[0, _RATE]
    for a in range(3):
        rate0[a] = 0.0
        rate0[3 + a] = -gravity[a]
    columns = np.empty((6, 6))
    if floating:
        k = index[0, 3]
        _root_columns(rot[0], columns)
        for a in range(6):
            s = six[0, _C, a] if moving else 0.0
            for b in range(6):
                s += columns[a, b] * acc[k + b]
            rate0[a] += s
    for i in range(1, n):
        j, kind = index[i, 0], index[i, 1]
        rate = six[i, _RATE]
        _shift_rate(six[j, _RATE], vec[i, _REACH], rate)
        if kind >= 4:
            _add_free_twist(kind, rot[i], acc, index[i, 3], rate)
        else:
            x = acc[index[i, 3]]
            kk = 3 if kind == 3 else 0
            e = vec[i, _AXIS]
            for a in range(3):
                rate[kk + a] += e[a] * x
        if moving:
            for a in range(6):
                rate[a] += six[i, _C, a]
    for i in range(0 if floating else 1, n):
        m = block[i, 0]
        rate = six[i, _RATE]
        for a in range(6):
            s = six[i, _B, a] if moving else 0.0
            for b in range(6):
                s += m[a, b] * rate[b]
            six[i, _WRENCH, a] = s
    load = np.empty(6)
    for i in range(n - 1, 0, -1):
        if index[i, 1] >= 4:
            _free_load(index[i, 1], rot[i], six[i, _WRENCH], load)
            for a in range(_width(index[i, 1])):
                out[index[i, 3] + a] = load[a]
        else:
            out[index[i, 3]] = _p_dot(index[i, 1], vec[i, _AXIS], six[i, _WRENCH])
        j = index[i, 0]
        if j > 0 or floating:
            _add_shifted_wrench(six[j, _WRENCH], six[i, _WRENCH], vec[i, _REACH])
    if floating:
        k = index[0, 3]
        for a in range(6):
            s = 0.0
            for r in range(6):
                s += columns[r, a] * six[0, _WRENCH, r]
            out[k + a] = s


@njit(cache=True)  # not inlined: the 1-DoF loops stay small
def _free_diagonal(c, r, k, out, kind=4):
    """A free body's diagonal entries: the subtree's mass m (linear), R_aᵀ I_O R_a (angular).

    A ball joint has the three angular ones only.
    """
    angular = k + 3 if kind == 4 else k
    for a in range(3):
        if kind == 4:
            out[k + a] = c[0]
        x, y, z = r[0, a], r[1, a], r[2, a]
        out[angular + a] = (
            c[4] * x * x
            + c[5] * y * y
            + c[6] * z * z
            + 2.0 * (c[7] * x * y + c[8] * x * z + c[9] * y * z)
        )


# -- entry points: one compiled call per operation ----------------------------------------


@njit(cache=True, error_model="numpy")  # a zero diagonal entry gives δ = inf, not an error
def gim_diagonal(q, index, geometry, floating, rot, vec, comp, out):
    """Diag M(q) = p_iᵀ M̃_i p_i (Shah & Saha 2013, Eqs. 11–13) into ``out``, O(n).

    Only the parts of the composite mass matrix M̃_i that its diagonal reads are carried:
    the subtree's mass m, first moment h = Σ m_k d_k and rotational inertia I_O about O_i
    (world axes), ``comp[i] = (m, h, I_xx, I_yy, I_zz, I_xy, I_xz, I_yz)``. Moving a child's
    from O_c to O_i (r = O_c − O_i): h += m r, I_O += m (|r|² 1 − r rᵀ) + 2 (r·h) 1 − r hᵀ −
    h rᵀ (h the child's, before the move). M_ii = e_iᵀ I_O e_i (revolute) or m (prismatic);
    the free-flyer's six are m (linear) and R_kᵀ I_O R_k (angular).

    Returns δ = max M_ii / min M_ii (Sec. 4), so that a watch needs nothing else.
    """
    _poses(q, index, geometry, floating, rot, vec)
    n = index.shape[0]
    t = np.empty((3, 3))
    for i in range(0 if floating else 1, n):
        g = geometry[i]
        m = g[15]
        r = rot[i]
        d0 = r[0, 0] * g[16] + r[0, 1] * g[17] + r[0, 2] * g[18]
        d1 = r[1, 0] * g[16] + r[1, 1] * g[17] + r[1, 2] * g[18]
        d2 = r[2, 0] * g[16] + r[2, 1] * g[17] + r[2, 2] * g[18]
        for a in range(3):  # T = R I
            for k in range(3):
                t[a, k] = r[a, 0] * g[19 + k] + r[a, 1] * g[22 + k] + r[a, 2] * g[25 + k]
        dd = d0 * d0 + d1 * d1 + d2 * d2
        c = comp[i]
        c[0], c[1], c[2], c[3] = m, m * d0, m * d1, m * d2
        # I_O = R I Rᵀ + m (|d|² 1 − d dᵀ)
        c[4] = t[0, 0] * r[0, 0] + t[0, 1] * r[0, 1] + t[0, 2] * r[0, 2] + m * (dd - d0 * d0)
        c[5] = t[1, 0] * r[1, 0] + t[1, 1] * r[1, 1] + t[1, 2] * r[1, 2] + m * (dd - d1 * d1)
        c[6] = t[2, 0] * r[2, 0] + t[2, 1] * r[2, 1] + t[2, 2] * r[2, 2] + m * (dd - d2 * d2)
        c[7] = t[0, 0] * r[1, 0] + t[0, 1] * r[1, 1] + t[0, 2] * r[1, 2] - m * d0 * d1
        c[8] = t[0, 0] * r[2, 0] + t[0, 1] * r[2, 1] + t[0, 2] * r[2, 2] - m * d0 * d2
        c[9] = t[1, 0] * r[2, 0] + t[1, 1] * r[2, 1] + t[1, 2] * r[2, 2] - m * d1 * d2
    for i in range(n - 1, 0, -1):
        c = comp[i]
        e0, e1, e2 = vec[i, _AXIS, 0], vec[i, _AXIS, 1], vec[i, _AXIS, 2]
        if index[i, 1] >= 4:
            _free_diagonal(c, rot[i], index[i, 3], out, index[i, 1])
        elif index[i, 1] == 3:
            out[index[i, 3]] = c[0]
        else:
            out[index[i, 3]] = (
                c[4] * e0 * e0
                + c[5] * e1 * e1
                + c[6] * e2 * e2
                + 2.0 * (c[7] * e0 * e1 + c[8] * e0 * e2 + c[9] * e1 * e2)
            )
        j = index[i, 0]
        if j > 0 or floating:
            p = comp[j]
            r0, r1, r2 = vec[i, _REACH, 0], vec[i, _REACH, 1], vec[i, _REACH, 2]
            m, h0, h1, h2 = c[0], c[1], c[2], c[3]
            rr = r0 * r0 + r1 * r1 + r2 * r2
            rh = r0 * h0 + r1 * h1 + r2 * h2
            p[0] += m
            p[1] += h0 + m * r0
            p[2] += h1 + m * r1
            p[3] += h2 + m * r2
            p[4] += c[4] + m * (rr - r0 * r0) + 2.0 * (rh - r0 * h0)
            p[5] += c[5] + m * (rr - r1 * r1) + 2.0 * (rh - r1 * h1)
            p[6] += c[6] + m * (rr - r2 * r2) + 2.0 * (rh - r2 * h2)
            p[7] += c[7] - m * r0 * r1 - r0 * h1 - h0 * r1
            p[8] += c[8] - m * r0 * r2 - r0 * h2 - h0 * r2
            p[9] += c[9] - m * r1 * r2 - r1 * h2 - h1 * r2
    if floating:
        _free_diagonal(comp[0], rot[0], index[0, 3], out)
    largest, smallest = out[0], out[0]
    for k in range(out.shape[0]):
        largest = max(largest, out[k])
        smallest = min(smallest, out[k])
    return largest / smallest


@njit(cache=True)
def configure(q, index, geometry, floating, rot, vec, block, six, scal, root):
    """Kinematics, body mass matrices and the articulated factor at q, for the products.

    Returns whether M(q) is positive definite (every pivot > 0).
    """
    _kinematics(q, index, geometry, floating, rot, vec, block)
    return _factor(index, floating, rot, vec, block, six, scal, root, 0.0)


@njit(cache=True)
def kinematics(q, index, geometry, floating, rot, vec, block):
    """Poses and body mass matrices at q: all that `gim_product` reads."""
    _kinematics(q, index, geometry, floating, rot, vec, block)


@njit(cache=True)
def factor_shifted(shift, index, floating, rot, vec, block, six, scal, root):
    """The articulated factor of M(q) − shift·1 after `kinematics`, for `gim_solve`.

    `gim_solve` then gives (M − shift·1)⁻¹ y. Returns whether every pivot is positive,
    i.e. (Sylvester's law of inertia) whether shift < λmin(M).
    """
    return _factor(index, floating, rot, vec, block, six, scal, root, shift)


@njit(cache=True)
def gim_product(x, index, floating, rot, vec, block, six, out):
    """M(q) x at the configured q (Newton–Euler from rest, no gravity), O(n)."""
    _newton_euler_pass(x, np.zeros(3), False, floating, index, rot, vec, block, six, out)


@njit(cache=True)
def gim_solve(y, index, floating, rot, vec, block, six, scal, root, out):
    """M(q)⁻¹ y at the configured q (articulated bodies from rest, no gravity), O(n)."""
    _articulated_pass(y, np.zeros(3), False, floating, index, rot, vec, block, six, scal, root, out)


@njit(cache=True)
def forward_dynamics(
    q, v, tau, gravity, index, geometry, floating, rot, vec, block, six, scal, root, out
):
    """q̈ = M(q)⁻¹ (τ − C(q, q̇) q̇ + g(q)) into ``out``; False when M(q) is singular."""
    _kinematics(q, index, geometry, floating, rot, vec, block)
    ok = _factor(index, floating, rot, vec, block, six, scal, root, 0.0)
    moving = _velocity_terms(v, index, geometry, floating, rot, vec, six)
    _articulated_pass(tau, gravity, moving, floating, index, rot, vec, block, six, scal, root, out)
    return ok


@njit(cache=True)
def forward_dynamics_factored(
    v, tau, gravity, index, geometry, floating, rot, vec, block, six, scal, root, out
):
    """`forward_dynamics` at the q of the last `configure` (factor kept)."""
    moving = _velocity_terms(v, index, geometry, floating, rot, vec, six)
    _articulated_pass(tau, gravity, moving, floating, index, rot, vec, block, six, scal, root, out)


@njit(cache=True)
def inverse_dynamics(q, v, a, gravity, index, geometry, floating, rot, vec, block, six, out):
    """τ = M(q) q̈ + C(q, q̇) q̇ − g(q) into ``out`` (Saha's DeNOC inverse dynamics)."""
    _kinematics(q, index, geometry, floating, rot, vec, block)
    moving = _velocity_terms(v, index, geometry, floating, rot, vec, six)
    _newton_euler_pass(a, gravity, moving, floating, index, rot, vec, block, six, out)
