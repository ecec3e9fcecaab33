"""Closed forms the tests compare with, written here from the rod formulas (no gimwatch code).

A planar chain of homogeneous rods (joints about z, rod k along its local x, centre of mass at
mid-rod, own inertia ``m (3 r² + l²) / 12`` about z). With absolute angles ``φ = cumsum(q)``
the centre of rod k is ``c_k = Σ_{a<k} l_a e(φ_a) + (l_k/2) e(φ_k)``, ``e(φ) = (cos φ, sin φ)``.

* ``rod_chain_gim``: M(q) from the kinetic energy ``½ φ̇ᵀ D φ̇``,
  ``D_ab = I_a δ_ab + l_a l_b (m_b/2 + S_{b+1}) cos(φ_a − φ_b)`` for a < b (symmetric),
  ``D_aa = I_a + l_a² (m_a/4 + S_{a+1})``, ``S_j = Σ_{k≥j} m_k``, and ``M = Tᵀ D T`` with T
  the lower-triangular ones (φ = T q). Vectorised: O(n²) memory, fine to n ≈ 2,000.
* ``rod_chain_energy``: kinetic ``Σ ½ m_k |ċ_k|² + ½ I_k φ̇_k²`` from the centre velocities
  (not from D) and potential ``−Σ m_k g·c_k``.
* ``straight_chain_pencil``: for the straight chain (q = 0) M = P A Pᵀ with A tridiagonal and
  P = (Tᵀ)², so M's eigenvalues are those of the banded pencil (A, (PᵀP)⁻¹): an O(n)
  reference for n = 10,000 where a dense M would take 800 MB.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse
import scipy.sparse.linalg

__all__ = [
    "rod_chain_energy",
    "rod_chain_gim",
    "straight_chain_extreme_eigenvalues",
]


def _per_link(value, n: int) -> np.ndarray:
    return np.array(np.broadcast_to(np.asarray(value, dtype=float), (n,)))


def _suffix(values: np.ndarray) -> np.ndarray:
    """S_j = Σ_{k≥j} values_k, with a trailing 0 (length n + 1)."""
    return np.concatenate([np.cumsum(values[::-1])[::-1], [0.0]])


def rod_chain_gim(q, mass_kg=2.2, length_m=1.0, radius_m=0.0) -> np.ndarray:
    """M(q) of the planar rod chain (kg·m²), from the closed form in the module docstring."""
    q = np.asarray(q, dtype=float)
    n = q.size
    m, l, r = (_per_link(x, n) for x in (mass_kg, length_m, radius_m))
    own = m * (3 * r**2 + l**2) / 12
    tail = _suffix(m)
    g = m / 2 + tail[1:]
    index = np.arange(n)
    later = np.maximum.outer(index, index)
    mu = np.outer(l, l) * g[later]
    mu[index, index] = l**2 * (m / 4 + tail[1:])
    phi = np.cumsum(q)
    D = mu * np.cos(np.subtract.outer(phi, phi))
    D[index, index] += own
    # Tᵀ D T: (Tᵀ D T)_ij = Σ_{a≥i, b≥j} D_ab
    return np.cumsum(np.cumsum(D[::-1, ::-1], axis=0), axis=1)[::-1, ::-1]


def rod_chain_energy(q, v, *, mass_kg=2.2, length_m=1.0, radius_m=0.0, gravity=(0.0, -9.81)):
    """(kinetic, potential) energy in J of the planar rod chain at (q, v)."""
    q, v = np.asarray(q, dtype=float), np.asarray(v, dtype=float)
    n = q.size
    m, l, r = (_per_link(x, n) for x in (mass_kg, length_m, radius_m))
    phi, phidot = np.cumsum(q), np.cumsum(v)
    e = np.stack([np.cos(phi), np.sin(phi)], axis=1)
    e_perp = np.stack([-np.sin(phi), np.cos(phi)], axis=1)
    joints = np.vstack([[0.0, 0.0], np.cumsum(l[:, None] * e, axis=0)[:-1]])
    joint_velocity = np.vstack([[0.0, 0.0], np.cumsum((l * phidot)[:, None] * e_perp, axis=0)[:-1]])
    centres = joints + (l / 2)[:, None] * e
    centre_velocity = joint_velocity + (l / 2 * phidot)[:, None] * e_perp
    own = m * (3 * r**2 + l**2) / 12
    kinetic = 0.5 * np.sum(m * np.sum(centre_velocity**2, axis=1)) + 0.5 * np.sum(own * phidot**2)
    potential = -np.sum(m * (centres @ np.asarray(gravity, dtype=float)))
    return float(kinetic), float(potential)


def _straight_chain_pencil(n: int, mass_kg: float, length_m: float):
    """Banded (A, B) with eig(M(0)) = eig(A, B) for the uniform slender straight chain.

    At φ = 0, D = C + l² K with C = diag(I_a − l² m/4) and K_ab = g(max(a, b)),
    g(b) = m/2 + S_{b+1}. K = U diag(d) Uᵀ with U = Tᵀ (upper ones), d_k = g(k) − g(k+1)
    (g(n) = 0). Then M = Tᵀ D T = P A Pᵀ with P = (Tᵀ)², A = U⁻¹ C U⁻ᵀ + l² diag(d)
    (tridiagonal), and M x = λ x ⇔ A y = λ (PᵀP)⁻¹ y, y = Pᵀ x; (PᵀP)⁻¹ = P⁻¹ P⁻ᵀ is
    pentadiagonal because P⁻¹ = (U⁻¹)² has two bands.
    """
    m = np.full(n, float(mass_kg))
    l = float(length_m)
    tail = _suffix(m)
    g = np.concatenate([m / 2 + tail[1:], [0.0]])
    d = g[:-1] - g[1:]
    c = m * l**2 / 12 - l**2 * m / 4
    U_inv = scipy.sparse.diags([np.ones(n), -np.ones(n - 1)], [0, 1], format="csc")
    A = U_inv @ scipy.sparse.diags(c) @ U_inv.T + l**2 * scipy.sparse.diags(d)
    P_inv = U_inv @ U_inv
    B = P_inv @ P_inv.T
    return A.tocsc(), B.tocsc()


def _negative_count(A, B, sigma: float) -> int:
    """Eigenvalues of the pencil (A, B) below σ: negative pivots of LDLᵀ(A − σB) (Sylvester)."""
    lu = scipy.sparse.linalg.splu(
        (A - sigma * B).tocsc(),
        permc_spec="NATURAL",
        diag_pivot_thresh=0.0,
        options={"SymmetricMode": True},
    )
    return int(np.sum(lu.U.diagonal() < 0))


def straight_chain_extreme_eigenvalues(n: int, mass_kg: float = 2.2, length_m: float = 1.0):
    """(λmin, λmax) of M(0) of the uniform slender straight chain, in O(n) per step.

    A is well conditioned (its eigenvalues lie in [m l²/3, m l²]); the ill-conditioning of M
    sits in P. λmin: bisection on Sylvester's inertia of A − σB (the smallest eigenvalues are
    clustered within relative gaps ~1/n², where Lanczos crawls; bisection does not care).
    λmax: Lanczos on x ↦ P A Pᵀ x (P applied by suffix sums), whose top is well separated.
    """
    A, B = _straight_chain_pencil(n, mass_kg, length_m)
    low, high = 0.0, float(mass_kg) * float(length_m) ** 2  # λmin ≤ M_nn = m l²/3
    while high - low > 1e-15 * high:
        middle = 0.5 * (low + high)
        if _negative_count(A, B, middle) == 0:
            low = middle
        else:
            high = middle
    lambda_min = 0.5 * (low + high)

    def suffix(x):
        return np.cumsum(x[::-1])[::-1]

    def product(x):  # P A Pᵀ x with P = (Tᵀ)²: Tᵀ x = suffix sums, T x = prefix sums
        x = np.ravel(x)
        return suffix(suffix(A @ np.cumsum(np.cumsum(x))))

    operator = scipy.sparse.linalg.LinearOperator((n, n), matvec=product, dtype=float)
    start = np.random.default_rng(0).standard_normal(n)
    lambda_max = scipy.sparse.linalg.eigsh(operator, k=1, which="LA", v0=start, tol=0)[0][0]
    return float(lambda_min), float(lambda_max)
