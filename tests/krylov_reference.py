"""The κ tracker's former Python twin of its Krylov engine, kept as a test reference only.

Thick-restart Lanczos written as a plain loop (one Python call per product), as the library
had it before the engine became one reverse-communication step
(`gimwatch.metrics.tracker.krylov.advance`). The tests check that the library's engine takes the
same steps and returns the same numbers.
"""

from collections.abc import Callable

import numpy as np

from gimwatch.metrics.tracker.krylov import (
    Workspace,
    _h_column,
    _orthonormalize_into,
    ritz_step,
)


def leading_reference(
    apply: Callable[[np.ndarray], np.ndarray],
    starts: np.ndarray,
    workspace: Workspace,
    ritz_out: np.ndarray,
    *,
    rtol: float,
    budget: int,
    keep: int,
    check_every: int = 4,
) -> tuple[float, float, bool, int]:
    """The old `leading_python`: `leading` for a Python callable (σ = 0).

    Same algorithm and returns; for providers other than DeNOC's (Pinocchio's RNEA/ABA,
    test operators), one Python call per product.
    """
    V, AV, H, vectors = workspace.arrays()
    n, size = starts.shape[1], V.shape[0]
    residual, spare = vectors[1], vectors[2]
    m = used = 0
    for start in starts:
        if m < size and _orthonormalize_into(V, m, np.ascontiguousarray(start), spare):
            AV[m] = apply(V[m].copy())
            _h_column(V, AV, H, m)
            m, used = m + 1, used + 1
    while True:
        restart = m + check_every > size
        theta, estimate, grown = ritz_step(V, AV, H, m, keep, 0.0, restart, residual, ritz_out)
        converged = m == n or (theta > 0 and estimate <= rtol)
        if converged or used >= budget:
            return float(theta), float(estimate), bool(converged), used
        m = grown
        if m >= n or not _orthonormalize_into(V, m, residual, spare):
            return float(theta), float(estimate), False, used
        for _ in range(check_every):
            AV[m] = apply(V[m].copy())
            used += 1
            _h_column(V, AV, H, m)
            m += 1
            if m == size or used >= budget or not _orthonormalize_into(V, m, AV[m - 1], spare):
                break
