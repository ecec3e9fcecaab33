"""The largest stable timestep h* of an integrator on a linearised robot, and the mode that sets it.

ρ(h) is the spectral radius of the one-step map Φ(h) (`gimwatch.stability.step_maps`). The
integration is stable at h when ρ(h) ≤ 1 (within `RHO_TOLERANCE`: an unheld coordinate has a
double eigenvalue 1, which float64 finds only to √eps). h* is the first h at which ρ exceeds 1:
h is scanned upward on a log grid (`SCAN_PER_DECADE` points a decade from `H_MIN_S` to
`H_MAX_S`, so that a stable window above an unstable one is not taken for h*), then the crossing
is bisected to `RELATIVE_TOLERANCE`. A held configuration unstable in continuous time (an
eigenvalue of A with a positive real part: gravity stronger than the servos) has h* = 0; one
stable up to `H_MAX_S` has h* = ∞.

The critical mode is the eigenvector of Φ just above h* with the largest |λ|: its joint
participations (share of |Δq|²), its frequency ω = √(φᴴKφ / φᴴMφ), and what limits it:
``"explicit damping"`` when taking away the damping the integrator treats explicitly raises h*
(by more than 5 %), ``"stiffness"`` otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gimwatch.stability.linear_system import LinearSystem
from gimwatch.stability.step_maps import EXPLICIT_DAMPING, step_map

__all__ = ["CriticalMode", "critical_mode", "max_stable_timestep", "spectral_radius"]

RHO_TOLERANCE = 1e-6
H_MIN_S, H_MAX_S = 1e-8, 10.0
SCAN_PER_DECADE = 24
RELATIVE_TOLERANCE = 1e-7
#: h* raised by more than this factor without explicit damping: explicit damping limits it.
DAMPING_LIMITS = 1.05


def spectral_radius(system: LinearSystem, integrator: str, h: float) -> float:
    """ρ(Φ(h)), the largest |eigenvalue| of the one-step map."""
    return float(np.max(np.abs(np.linalg.eigvals(step_map(system, integrator, h)))))


def _stable(system: LinearSystem, integrator: str, h: float) -> bool:
    rho = spectral_radius(system, integrator, h)
    return bool(np.isfinite(rho) and rho <= 1.0 + RHO_TOLERANCE)


def continuous_unstable(system: LinearSystem) -> bool:
    """Whether the held configuration itself is unstable (an eigenvalue of A with Re > 0)."""
    rates = np.linalg.eigvals(system.state_matrix())
    scale = max(1.0, float(np.max(np.abs(rates))))
    return bool(np.max(rates.real) > 1e-9 * scale)


def max_stable_timestep(system: LinearSystem, integrator: str) -> float:
    """h* in seconds: 0 if the held configuration is unstable, ∞ if stable up to H_MAX_S."""
    if continuous_unstable(system):
        return 0.0
    grid = np.logspace(
        np.log10(H_MIN_S), np.log10(H_MAX_S), int(SCAN_PER_DECADE * np.log10(H_MAX_S / H_MIN_S)) + 1
    )
    low = 0.0
    for h in grid:
        if not _stable(system, integrator, float(h)):
            high = float(h)
            break
        low = float(h)
    else:
        return float("inf")
    while high - low > RELATIVE_TOLERANCE * high:
        middle = 0.5 * (low + high)
        if _stable(system, integrator, middle):
            low = middle
        else:
            high = middle
    return low


@dataclass(frozen=True)
class CriticalMode:
    """The mode that goes unstable first as h grows past h*.

    Attributes:
        participation: Share of each coordinate in the mode's |Δq|² (sums to 1).
        frequency_rad_s: ω = √(φᴴKφ / φᴴMφ), the mode's undamped frequency.
        limited_by: ``"stiffness"`` or ``"explicit damping"``.
        h_without_explicit_damping_s: h* with the explicitly-treated damping taken away.
    """

    participation: np.ndarray
    frequency_rad_s: float
    limited_by: str
    h_without_explicit_damping_s: float


def _without_explicit_damping(system: LinearSystem, integrator: str) -> LinearSystem:
    explicit = EXPLICIT_DAMPING[integrator]
    zero = np.zeros_like(system.mass)
    if explicit == "actuator":
        return LinearSystem(system.mass, system.stiffness, zero, system.joint_damping)
    if explicit == "all":
        return LinearSystem(system.mass, system.stiffness, zero, zero)
    return system


def critical_mode(system: LinearSystem, integrator: str, h_star: float) -> CriticalMode | None:
    """The mode that crosses |λ| = 1 at h* (None when h* is 0 or ∞)."""
    if not 0.0 < h_star < np.inf:
        return None
    values, vectors = np.linalg.eig(step_map(system, integrator, h_star * 1.001))
    phi = vectors[: system.n, int(np.argmax(np.abs(values)))]
    weight = np.abs(phi) ** 2
    participation = weight / weight.sum() if weight.sum() > 0 else weight
    omega2 = np.real(np.conj(phi) @ system.stiffness @ phi) / np.real(
        np.conj(phi) @ system.mass @ phi
    )
    free = _without_explicit_damping(system, integrator)
    h_free = h_star if free is system else max_stable_timestep(free, integrator)
    limited = "explicit damping" if h_free > DAMPING_LIMITS * h_star else "stiffness"
    return CriticalMode(
        participation=participation,
        frequency_rad_s=float(np.sqrt(max(omega2, 0.0))),
        limited_by=limited,
        h_without_explicit_damping_s=float(h_free),
    )


def undamped_bound(system: LinearSystem) -> float:
    """2/ω_max, symplectic Euler's h* without damping (ω² the eigenvalues of M⁻¹K)."""
    omega2 = np.max(np.real(np.linalg.eigvals(np.linalg.solve(system.mass, system.stiffness))))
    return float(2.0 / np.sqrt(omega2)) if omega2 > 0 else float("inf")
