"""High-precision (mpmath) forward dynamics of planar rod chains, built without Pinocchio.

The reference follows the closed-form Lagrangian of a planar chain of homogeneous rods
(joints about z, rod k along its local x, centre of mass at mid-rod), written in the
absolute angles φ = T q (T lower-triangular ones, φ_k = q_1 + … + q_k):

* kinetic energy ``T = ½ φ̇ᵀ D(φ) φ̇`` with
  ``D_ab = I_a δ_ab + μ_ab cos(φ_a − φ_b)``, ``I_a`` the rod's own inertia about z and
  ``μ_ab = Σ_k m_k r_ka r_kb``, where ``r_ka = l_a`` (k > a), ``l_a/2`` (k = a), 0 (k < a)
  is the lever of angle a on the centre of rod k; closed form
  ``μ_ab = l_a l_b (m_b/2 + S_{b+1})`` for a < b and ``μ_aa = l_a² (m_a/4 + S_{a+1})`` with
  ``S_j = Σ_{k≥j} m_k``;
* velocity forces ``h_a = Σ_b μ_ab sin(φ_a − φ_b) φ̇_b²``;
* gravity ``G_a = −(g · e⊥(φ_a)) Σ_k m_k r_ka``, ``e⊥(φ) = (−sin φ, cos φ)``, g in the plane.

In joint coordinates ``M(q) = Tᵀ D T`` (the GIM of Shah & Saha 2013, Eq. 5 for this chain)
and ``q̈ = M⁻¹ (τ − Tᵀ (h + G))``, solved by LU in mpmath at ``dps`` digits (50 by
default). Inputs are taken as exact binary floats, so the only error left in the result
is mpmath's, about 10^−dps · κ.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import mpmath
import numpy as np
import numpy.typing as npt

from gimwatch.errors import InputError
from gimwatch.model.chains import ChainSpec

__all__ = ["PlanarChainReference", "planar_reference"]

REFERENCE_DIGITS = 50


def _check_planar(spec: ChainSpec) -> None:
    if any(axis != "z" for axis in spec.axes) or any(k != "revolute" for k in spec.joint_types):
        raise InputError(
            "the chain", "planar with revolute joints about z (axes='planar')", spec.layout
        )


@dataclass(frozen=True)
class PlanarChainReference:
    """The planar rod chain in mpmath: M(q), the bias forces and q̈ at ``dps`` digits.

    Attributes:
        spec: The chain (planar, revolute joints about z).
        gravity_m_s2: Gravity in the chain's plane, (g_x, g_y) in m/s².
        dps: Decimal digits of the mpmath arithmetic.
    """

    spec: ChainSpec
    gravity_m_s2: tuple[float, float] = (0.0, -9.81)
    dps: int = REFERENCE_DIGITS

    def __post_init__(self) -> None:
        _check_planar(self.spec)
        if len(self.gravity_m_s2) != 2:
            raise InputError("gravity_m_s2", "(g_x, g_y) in the chain's plane", self.gravity_m_s2)
        if not 15 <= self.dps <= 1000:
            raise InputError("dps", "between 15 and 1000", self.dps)

    def _vector(self, name: str, values: npt.ArrayLike) -> list:
        array = np.asarray(values, dtype=float)
        if array.shape != (self.spec.n,) or not np.all(np.isfinite(array)):
            raise InputError(name, f"a finite vector of {self.spec.n} numbers", array.shape)
        return [mpmath.mpf(float(x)) for x in array]

    def _parts(self, q: npt.ArrayLike, v: npt.ArrayLike | None):
        n = self.spec.n
        mp = mpmath.mp
        m = [mp.mpf(x) for x in self.spec.masses_kg]
        l = [mp.mpf(x) for x in self.spec.lengths_m]
        r = [mp.mpf(x) for x in self.spec.radii_m]
        own = [m[k] * (3 * r[k] ** 2 + l[k] ** 2) / 12 for k in range(n)]  # Izz of rod k
        tail = [mp.mpf(0)] * (n + 1)  # tail[j] = S_j = Σ_{k >= j} m_k
        for k in range(n - 1, -1, -1):
            tail[k] = tail[k + 1] + m[k]
        phi, total = [], mp.mpf(0)
        for x in self._vector("q", q):
            total += x
            phi.append(total)
        mu = mp.matrix(n, n)
        for a in range(n):
            mu[a, a] = l[a] ** 2 * (m[a] / 4 + tail[a + 1])
            for b in range(a + 1, n):
                mu[a, b] = mu[b, a] = l[a] * l[b] * (m[b] / 2 + tail[b + 1])
        cos = [[mp.cos(phi[a] - phi[b]) for b in range(n)] for a in range(n)]
        D = mp.matrix(n, n)
        for a in range(n):
            for b in range(n):
                D[a, b] = mu[a, b] * cos[a][b]
            D[a, a] += own[a]
        parts = {"D": D, "phi": phi}
        if v is not None:
            phidot, total = [], mp.mpf(0)
            for x in self._vector("v", v):
                total += x
                phidot.append(total)
            gx, gy = (mp.mpf(float(g)) for g in self.gravity_m_s2)
            bias = []
            for a in range(n):
                h = mp.fsum(mu[a, b] * mp.sin(phi[a] - phi[b]) * phidot[b] ** 2 for b in range(n))
                lever = l[a] * (m[a] / 2 + tail[a + 1])  # Σ_k m_k r_ka
                bias.append(h - (-gx * mp.sin(phi[a]) + gy * mp.cos(phi[a])) * lever)
            parts["bias"] = bias
        return parts

    def gim(self, q: npt.ArrayLike) -> mpmath.matrix:
        """M(q) = Tᵀ D(φ) T in mpmath (kg·m²)."""
        with mpmath.workdps(self.dps):
            D = self._parts(q, None)["D"]
            return _t_transpose_a_t(D)

    def bias(self, q: npt.ArrayLike, v: npt.ArrayLike) -> list:
        """Tᵀ (h + G): the joint torques of velocity and gravity forces (N·m), in mpmath."""
        with mpmath.workdps(self.dps):
            return _t_transpose(self._parts(q, v)["bias"])

    def forward_dynamics(
        self, q: npt.ArrayLike, v: npt.ArrayLike, tau: npt.ArrayLike
    ) -> np.ndarray:
        """q̈ = M(q)⁻¹ (τ − Tᵀ (h + G)), solved in mpmath, rounded to float64 (rad/s²)."""
        with mpmath.workdps(self.dps):
            parts = self._parts(q, v)
            M = _t_transpose_a_t(parts["D"])
            torques = self._vector("tau", tau)
            bias = _t_transpose(parts["bias"])
            rhs = [t - b for t, b in zip(torques, bias, strict=True)]
            a = mpmath.lu_solve(M, mpmath.matrix(rhs))
            return np.array([float(a[i]) for i in range(self.spec.n)])


def _t_transpose(x: Sequence) -> list:
    """Tᵀ x for T lower-triangular ones: suffix sums."""
    out, total = [None] * len(x), mpmath.mpf(0)
    for i in range(len(x) - 1, -1, -1):
        total += x[i]
        out[i] = total
    return out


def _t_transpose_a_t(A: mpmath.matrix) -> mpmath.matrix:
    """Tᵀ A T: (Tᵀ A T)_ij = Σ_{a≥i, b≥j} A_ab, by suffix sums over rows then columns."""
    n = A.rows
    out = mpmath.matrix(n, n)
    col = mpmath.matrix(n, n)
    for i in range(n):
        total = mpmath.mpf(0)
        for j in range(n - 1, -1, -1):
            total += A[i, j]
            col[i, j] = total
    for j in range(n):
        total = mpmath.mpf(0)
        for i in range(n - 1, -1, -1):
            total += col[i, j]
            out[i, j] = total
    return out


def planar_reference(
    spec: ChainSpec,
    q: npt.ArrayLike,
    v: npt.ArrayLike,
    tau: npt.ArrayLike,
    *,
    gravity_m_s2: tuple[float, float] = (0.0, -9.81),
    dps: int = REFERENCE_DIGITS,
) -> np.ndarray:
    """q̈ of a planar rod chain at ``dps`` digits (see `PlanarChainReference`)."""
    gravity = (float(gravity_m_s2[0]), float(gravity_m_s2[1]))
    return PlanarChainReference(spec, gravity_m_s2=gravity, dps=dps).forward_dynamics(q, v, tau)
