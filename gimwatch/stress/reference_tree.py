"""High-precision (mpmath) forward and inverse dynamics of any kinematic tree, without Pinocchio.

The planar closed form of [`gimwatch.stress.reference_planar`][gimwatch.stress.reference_planar]
covers planar revolute chains only; this
module covers every tree DeNOC reads (revolute, continuous and prismatic joints, fixed or
free-flyer base). It runs Featherstone's articulated-body algorithm (ABA, *Rigid Body
Dynamics Algorithms* 2008, Table 7.1) and recursive Newton–Euler algorithm (RNEA, Table 5.1)
in body coordinates with spatial vectors ``[ω; v]``, all in mpmath at ``dps`` digits (50 by
default), so its own round-off is ~10^−dps·κ, far below float64's κ·eps.

What it shares with the code it checks: the URDF is read into a
[`BodyTree`][gimwatch.denoc.BodyTree] by DeNOC's reader (yourdfpy; fixed links merged).
Everything after that — kinematics, spatial algebra, the recursions, the arithmetic — is
written here, independently of Pinocchio and of DeNOC's recursions (which use world-frame
composite inertias and a UDUᵀ elimination, not body-frame articulated inertias). Inputs are
taken as exact binary floats. ``rnea(q, v, aba(q, v, τ)) = τ`` to ~10^−(dps−5) checks it
against itself, and the planar closed form against
[`gimwatch.stress.reference_planar`][gimwatch.stress.reference_planar].
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import mpmath
import numpy as np
import numpy.typing as npt

from gimwatch.denoc.tree import BodyTree
from gimwatch.errors import InputError

__all__ = ["TreeReference"]

REFERENCE_DIGITS = 50


def _mp(values) -> list:
    return [mpmath.mpf(float(x)) for x in values]


def _cross(a: list, b: list) -> list:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def _matvec(R: list, x: list) -> list:
    return [R[i][0] * x[0] + R[i][1] * x[1] + R[i][2] * x[2] for i in range(3)]


def _matmul(A: list, B: list) -> list:
    n, m, k = len(A), len(B[0]), len(B)
    return [[mpmath.fsum(A[i][r] * B[r][j] for r in range(k)) for j in range(m)] for i in range(n)]


def _transpose(A: list) -> list:
    return [list(row) for row in zip(*A, strict=True)]


def _rotation(axis: list, c, s) -> list:
    """Rodrigues: R = cI + s[a]× + (1 − c) a aᵀ for a unit axis a."""
    x, y, z = axis
    t = 1 - c
    return [
        [c + t * x * x, t * x * y - s * z, t * x * z + s * y],
        [t * x * y + s * z, c + t * y * y, t * y * z - s * x],
        [t * x * z - s * y, t * y * z + s * x, c + t * z * z],
    ]


def _quaternion(x, y, z, w) -> list:
    return [
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ]


def _motion_transform(E: list, r: list) -> list:
    """6×6 ``X`` taking a motion vector from the parent frame to a child frame at (E, r).

    ``ω_c = Eᵀ ω_p``, ``v_c = Eᵀ (v_p − r × ω_p)`` (Featherstone Eq. 2.24).
    """
    Et = _transpose(E)
    rx = [[0, -r[2], r[1]], [r[2], 0, -r[0]], [-r[1], r[0], 0]]
    lower = _matmul(Et, rx)
    X = [[mpmath.mpf(0)] * 6 for _ in range(6)]
    for i in range(3):
        for j in range(3):
            X[i][j] = X[i + 3][j + 3] = Et[i][j]
            X[i + 3][j] = -lower[i][j]
    return X


def _apply(X: list, x: list) -> list:
    return [mpmath.fsum(X[i][j] * x[j] for j in range(6)) for i in range(6)]


def _apply_t(X: list, x: list) -> list:
    return [mpmath.fsum(X[j][i] * x[j] for j in range(6)) for i in range(6)]


def _cross_motion(v: list, m: list) -> list:
    w, u = v[:3], v[3:]
    return _cross(w, m[:3]) + [
        a + b for a, b in zip(_cross(w, m[3:]), _cross(u, m[:3]), strict=True)
    ]


def _cross_force(v: list, f: list) -> list:
    w, u = v[:3], v[3:]
    return [a + b for a, b in zip(_cross(w, f[:3]), _cross(u, f[3:]), strict=True)] + _cross(
        w, f[3:]
    )


class TreeReference:
    """ABA and RNEA of a `BodyTree` in mpmath, in Pinocchio's coordinate layout.

    Args:
        tree: The body tree (from [`read_body_tree`][gimwatch.denoc.read_body_tree]).
        q_index: Index of each moving joint's first q coordinate, by joint name
            (``root_joint`` for the free-flyer: x, y, z, qx, qy, qz, qw).
        v_index: Index of each moving joint's first velocity coordinate, by joint name
            (the free-flyer's six are local linear then local angular, as Pinocchio).
        gravity: Gravity in the world (m/s²).
        dps: Decimal digits of the arithmetic.
    """

    def __init__(
        self,
        tree: BodyTree,
        q_index: Mapping[str, int],
        v_index: Mapping[str, int],
        *,
        gravity: npt.ArrayLike = (0.0, 0.0, -9.81),
        dps: int = REFERENCE_DIGITS,
    ) -> None:
        names = [name for name in tree.joint_names if name]
        if set(names) != set(q_index) or set(names) != set(v_index):
            raise InputError("q_index and v_index", f"keyed by the joints {names}", list(q_index))
        if not 15 <= dps <= 1000:
            raise InputError("dps", "between 15 and 1000", dps)
        self.tree, self.dps = tree, dps
        self.q_index = [q_index.get(name, -1) for name in tree.joint_names]
        self.v_index = [v_index.get(name, -1) for name in tree.joint_names]
        self.nv = 6 * tree.floating + tree.size - 1
        self.nq = 7 * tree.floating + sum(2 if k == 2 else 1 for k in tree.kind[1:])
        self.gravity = np.asarray(gravity, dtype=float)
        with mpmath.workdps(dps):
            self._inertia = [self._spatial_inertia(i) for i in range(tree.size)]

    def _spatial_inertia(self, i: int) -> list:
        """[[I_c + m c̃ c̃ᵀ, m c̃], [m c̃ᵀ, m 1]] about the body origin (Featherstone Eq. 2.63)."""
        m = mpmath.mpf(float(self.tree.mass[i]))
        c = _mp(self.tree.com[i])
        Ic = [_mp(row) for row in self.tree.inertia[i]]
        cx = [[0, -c[2], c[1]], [c[2], 0, -c[0]], [-c[1], c[0], 0]]
        ccT = _matmul(cx, _transpose(cx))
        out = [[mpmath.mpf(0)] * 6 for _ in range(6)]
        for a in range(3):
            for b in range(3):
                out[a][b] = Ic[a][b] + m * ccT[a][b]
                out[a][b + 3] = m * cx[a][b]
                out[a + 3][b] = m * cx[b][a]
            out[a + 3][a + 3] = m
        return out

    def _check(self, name: str, x: npt.ArrayLike, size: int) -> np.ndarray:
        array = np.asarray(x, dtype=float)
        if array.shape != (size,) or not np.all(np.isfinite(array)):
            raise InputError(name, f"a finite vector of {size} numbers", array.shape)
        return array

    def _joints(self, q: np.ndarray):
        """Per body: motion transform from the parent, and the joint's subspace S (6 × k)."""
        tree = self.tree
        X: list[Any] = []  # None for a fixed base's world: mpmath matrices as nested lists
        S: list[Any] = []
        for i in range(tree.size):
            if i == 0:
                if tree.floating:
                    k = self.q_index[0]
                    E = _quaternion(*_mp(q[k + 3 : k + 7]))
                    X.append(_motion_transform(E, _mp(q[k : k + 3])))
                    eye = [[mpmath.mpf(int(a == b)) for b in range(6)] for a in range(6)]
                    S.append([row[3:] + row[:3] for row in eye])  # v = (linear, angular)
                else:
                    X.append(None)
                    S.append(None)
                continue
            axis = _mp(tree.axis[i])
            Rp = [_mp(row) for row in tree.placement_rotation[i]]
            r = _mp(tree.placement_translation[i])
            value = mpmath.mpf(float(q[self.q_index[i]]))
            zero = [mpmath.mpf(0)] * 3
            if tree.kind[i] == 3:  # prismatic: translate along the axis
                E = Rp
                r = [a + b for a, b in zip(r, _matvec(Rp, [value * x for x in axis]), strict=True)]
                column = zero + axis
            else:
                if tree.kind[i] == 2:
                    c, s = value, mpmath.mpf(float(q[self.q_index[i] + 1]))
                else:
                    c, s = mpmath.cos(value), mpmath.sin(value)
                E = _matmul(Rp, _rotation(axis, c, s))
                column = axis + zero
            X.append(_motion_transform(E, r))
            S.append([[x] for x in column])
        return X, S

    def _velocities(self, X, S, v: np.ndarray):
        """Body twists v_i, bias accelerations c_i = v_i × S q̇_i and joint rates q̇_i."""
        tree = self.tree
        twist: list[Any] = []
        bias: list[Any] = []
        rates: list[Any] = []
        for i in range(tree.size):
            if S[i] is None:
                twist.append([mpmath.mpf(0)] * 6)
                bias.append([mpmath.mpf(0)] * 6)
                rates.append([])
                continue
            k = self.v_index[i]
            qd = _mp(v[k : k + len(S[i][0])])
            joint = [mpmath.fsum(S[i][a][b] * qd[b] for b in range(len(qd))) for a in range(6)]
            parent = twist[tree.parent[i]] if i else [mpmath.mpf(0)] * 6
            vi = [a + b for a, b in zip(_apply(X[i], parent), joint, strict=True)]
            twist.append(vi)
            bias.append(_cross_motion(vi, joint))
            rates.append(qd)
        return twist, bias, rates

    def _base_acceleration(self) -> list:
        return [mpmath.mpf(0)] * 3 + [-x for x in _mp(self.gravity)]  # a_0 = −g (Eq. 5.15)

    def _frame_acceleration(self, i: int, X, acc) -> list:
        parent = self.tree.parent[i]
        return _apply(X[i], acc[parent] if i else self._base_acceleration())

    def inverse_dynamics(self, q: npt.ArrayLike, v: npt.ArrayLike, a: npt.ArrayLike) -> list:
        """τ = RNEA(q, v, a) in mpmath (Featherstone Table 5.1), public coordinate order."""
        q, v, a = (
            self._check(n, x, s)
            for n, x, s in (("q", q, self.nq), ("v", v, self.nv), ("a", a, self.nv))
        )
        tree = self.tree
        with mpmath.workdps(self.dps):
            X, S = self._joints(q)
            twist, bias, _ = self._velocities(X, S, v)
            acc, force = [], []
            for i in range(tree.size):
                if S[i] is None:
                    acc.append(self._base_acceleration())
                    force.append([mpmath.mpf(0)] * 6)
                    continue
                k = self.v_index[i]
                qdd = _mp(a[k : k + len(S[i][0])])
                joint = [
                    mpmath.fsum(S[i][r][b] * qdd[b] for b in range(len(qdd))) for r in range(6)
                ]
                ai = [
                    x + y + z
                    for x, y, z in zip(
                        self._frame_acceleration(i, X, acc), joint, bias[i], strict=True
                    )
                ]
                acc.append(ai)
                I = self._inertia[i]
                momentum = _apply(I, twist[i])
                force.append(
                    [
                        x + y
                        for x, y in zip(
                            _apply(I, ai), _cross_force(twist[i], momentum), strict=True
                        )
                    ]
                )
            tau = [mpmath.mpf(0)] * self.nv
            for i in range(tree.size - 1, 0 if not tree.floating else -1, -1):
                k = self.v_index[i]
                for b in range(len(S[i][0])):
                    tau[k + b] = mpmath.fsum(S[i][r][b] * force[i][r] for r in range(6))
                if i:
                    back = _apply_t(X[i], force[i])
                    p = tree.parent[i]
                    force[p] = [x + y for x, y in zip(force[p], back, strict=True)]
            return tau

    def forward_dynamics_mp(self, q: npt.ArrayLike, v: npt.ArrayLike, tau: npt.ArrayLike) -> list:
        """q̈ = ABA(q, v, τ) in mpmath (Featherstone Table 7.1), public coordinate order."""
        q, v, tau = (
            self._check(n, x, s)
            for n, x, s in (("q", q, self.nq), ("v", v, self.nv), ("tau", tau, self.nv))
        )
        with mpmath.workdps(self.dps):
            X, S = self._joints(q)
            twist, bias, _ = self._velocities(X, S, v)
            U, Dinv, u = self._articulated_pass(X, S, twist, bias, tau)
            return self._accelerations(X, S, bias, (U, Dinv, u))

    def _articulated_pass(self, X: list, S: list, twist: list, bias: list, tau) -> tuple:
        """Tip to root: each joint's U = IA·S, D⁻¹ = (SᵀU)⁻¹ and u = τ − Sᵀp (Table 7.1).

        Raises:
            InputError: A joint's D is not positive definite (it moves no mass).
        """
        tree = self.tree
        n = tree.size
        IA: list[Any] = [None] * n
        pA: list[Any] = [None] * n
        for i in range(n):
            IA[i] = [row[:] for row in self._inertia[i]]
            pA[i] = _cross_force(twist[i], _apply(self._inertia[i], twist[i]))
        U: list[Any] = [None] * n
        Dinv: list[Any] = [None] * n
        u: list[Any] = [None] * n
        for i in range(n - 1, -1, -1):
            if S[i] is None:
                continue
            k, width = self.v_index[i], len(S[i][0])
            Ui = _matmul(IA[i], S[i])  # 6 × width
            D = _matmul(_transpose(S[i]), Ui)
            if any(D[b][b] <= 0 for b in range(width)):
                raise InputError("M(q)", "positive definite (a joint moves no mass)", i)
            Dinv[i] = mpmath.inverse(mpmath.matrix(D)).tolist()
            St_p = [mpmath.fsum(S[i][r][b] * pA[i][r] for r in range(6)) for b in range(width)]
            u[i] = [mpmath.mpf(float(tau[k + b])) - St_p[b] for b in range(width)]
            U[i] = Ui
            if i == 0:
                continue
            UDinv = _matmul(Ui, Dinv[i])
            Ia = [
                [
                    IA[i][r][c] - mpmath.fsum(UDinv[r][b] * Ui[c][b] for b in range(width))
                    for c in range(6)
                ]
                for r in range(6)
            ]
            Ia_c = _apply(Ia, bias[i])
            UDu = [mpmath.fsum(UDinv[r][b] * u[i][b] for b in range(width)) for r in range(6)]
            pa = [pA[i][r] + Ia_c[r] + UDu[r] for r in range(6)]
            p = tree.parent[i]
            add = _matmul(_matmul(_transpose(X[i]), Ia), X[i])
            IA[p] = [[IA[p][r][c] + add[r][c] for c in range(6)] for r in range(6)]
            back = _apply_t(X[i], pa)
            pA[p] = [x + y for x, y in zip(pA[p], back, strict=True)]
        return U, Dinv, u

    def _accelerations(self, X: list, S: list, bias: list, factors: tuple) -> list:
        """Root to tip: q̈ of each joint from its U, D⁻¹ and u, and the body accelerations."""
        U, Dinv, u = factors
        qdd = [mpmath.mpf(0)] * self.nv
        acc: list[Any] = [None] * self.tree.size
        for i in range(self.tree.size):
            if S[i] is None:
                acc[i] = self._base_acceleration()
                continue
            k, width = self.v_index[i], len(S[i][0])
            ai = [x + y for x, y in zip(self._frame_acceleration(i, X, acc), bias[i], strict=True)]
            Ut_a = [mpmath.fsum(U[i][r][b] * ai[r] for r in range(6)) for b in range(width)]
            rhs = [u[i][b] - Ut_a[b] for b in range(width)]
            dd = [mpmath.fsum(Dinv[i][b][c] * rhs[c] for c in range(width)) for b in range(width)]
            for b in range(width):
                qdd[k + b] = dd[b]
            acc[i] = [
                ai[r] + mpmath.fsum(S[i][r][b] * dd[b] for b in range(width)) for r in range(6)
            ]
        return qdd

    def forward_dynamics(
        self, q: npt.ArrayLike, v: npt.ArrayLike, tau: npt.ArrayLike
    ) -> np.ndarray:
        """q̈ at ``dps`` digits, rounded to float64."""
        return np.array([float(x) for x in self.forward_dynamics_mp(q, v, tau)])
