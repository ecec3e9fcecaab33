"""Batched 3-vector and 6-vector helpers for the DeNOC recursions (numpy only).

Twists follow Saha's order ``t = [ω; v]`` (angular velocity, then the velocity of the body
origin O), wrenches ``w = [n; f]`` (moment about O, then force); all vectors are in world
axes. Every function accepts a leading batch dimension (``(k, 3)``, ``(k, 6, 6)``, ...) so one
call serves all bodies of one tree depth.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "accumulate",
    "body_mass_matrix",
    "cross",
    "rodrigues",
    "shift_mass_matrix",
    "shift_twist",
    "shift_wrench",
    "skew",
]


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a × b`` over the last axis (np.cross without its per-call overhead on tiny arrays)."""
    a0, a1, a2 = a[..., 0], a[..., 1], a[..., 2]
    b0, b1, b2 = b[..., 0], b[..., 1], b[..., 2]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-1)


def accumulate(target: np.ndarray, index: np.ndarray, values: np.ndarray) -> None:
    """``target[index] += values`` with repeated indices summed (np.add.at, fast path for 1)."""
    if len(index) == 1:
        target[index[0]] += values[0]
    else:
        np.add.at(target, index, values)


def skew(r: np.ndarray) -> np.ndarray:
    """Cross-product matrices ``[r]×`` of vectors ``r`` of shape ``(..., 3)``."""
    r = np.asarray(r, dtype=float)
    out = np.zeros((*r.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -r[..., 2], r[..., 1]
    out[..., 1, 0], out[..., 1, 2] = r[..., 2], -r[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -r[..., 1], r[..., 0]
    return out


def rodrigues(axis: np.ndarray, cos: np.ndarray, sin: np.ndarray) -> np.ndarray:
    """Rotations about unit ``axis`` (k, 3) by the angles with cosines/sines (k,).

    ``R = cos θ 1 + sin θ [e]× + (1 − cos θ) e eᵀ`` (Rodrigues' formula).
    """
    cos = np.asarray(cos, dtype=float)[..., None, None]
    sin = np.asarray(sin, dtype=float)[..., None, None]
    outer = axis[..., :, None] * axis[..., None, :]
    return cos * np.eye(3) + sin * skew(axis) + (1.0 - cos) * outer


def shift_twist(t: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Twist-propagation ``A t``: the twist ``[ω; v]`` at O moved to the point O + r.

    ``A = [[1, 0], [−[r]×, 1]]`` (Saha's twist-propagation matrix), i.e. ``v' = v + ω × r``.
    """
    out = np.array(t, dtype=float, copy=True)
    out[..., 3:] += cross(t[..., :3], r)
    return out


def shift_wrench(w: np.ndarray, r: np.ndarray) -> np.ndarray:
    """Transposed propagation ``Aᵀ w``: the wrench ``[n; f]`` at O + r moved back to O.

    ``Aᵀ = [[1, [r]×], [0, 1]]``, i.e. ``n' = n + r × f``.
    """
    out = np.array(w, dtype=float, copy=True)
    out[..., :3] += cross(r, w[..., 3:])
    return out


def shift_mass_matrix(M: np.ndarray, r: np.ndarray) -> np.ndarray:
    """``Aᵀ M A`` for mass matrices M (k, 6, 6) at O + r, giving them about O (Eq. 12 term)."""
    A = np.zeros((*r.shape[:-1], 6, 6))
    A[..., :, :] = np.eye(6)
    A[..., 3:, :3] = -skew(r)
    return np.swapaxes(A, -1, -2) @ M @ A


def body_mass_matrix(mass: np.ndarray, com: np.ndarray, inertia_com: np.ndarray) -> np.ndarray:
    """Saha's 6×6 mass matrix about the body origin O, in world axes.

    ``M = [[I_O, m [d]×], [−m [d]×, m 1]]`` with d the centre of mass from O and
    ``I_O = I_C − m [d]×²`` the inertia about O (parallel-axis theorem).

    Args:
        mass: Masses (k,), kg.
        com: Centres of mass relative to O (k, 3), world axes, m.
        inertia_com: Inertia tensors about the centre of mass (k, 3, 3), world axes, kg·m².
    """
    d = skew(com)
    m = np.asarray(mass, dtype=float)[..., None, None]
    M = np.zeros((*np.shape(mass), 6, 6))
    M[..., :3, :3] = inertia_com - m * (d @ d)
    M[..., :3, 3:] = m * d
    M[..., 3:, :3] = -m * d
    M[..., 3:, 3:] = m * np.eye(3)
    return M
