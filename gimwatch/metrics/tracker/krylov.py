"""The κ tracker's Krylov engine: thick-restart Lanczos for the leading eigenpair, compiled.

One routine, [`leading`][gimwatch.metrics.tracker.krylov.leading], serves every operator of
the [`tracker`][gimwatch.metrics.tracker.core]: the caller passes a block of start vectors
(the warm start), and the basis grows Lanczos-style — each new vector is A times the previous one,
orthogonalised twice against the basis (CGS2). Every ``check_every`` products, Rayleigh–Ritz on the
whole basis gives the leading Ritz pair (θ, y) and its residual r = A y − θ y, which restarts the
Lanczos sequence; a full basis (`MAX_BASIS`) is thick-restarted on the ``keep`` leading Ritz
vectors, whose products are combinations of the stored ones (no product is spent).

Stopping rule: the Kato–Temple bound ‖r‖² / (θ · gap), gap = θ − θ₂ from the Ritz values,
bounds the relative error of θ. For A = (M − σ·1)⁻¹ (shift-invert, θ = 1/(λ − σ)) the error
of λ = σ + 1/θ relative to λ is that bound divided by 1 + σθ, and the rule is applied to it:
converged when ‖r‖² / (θ · gap · (1 + σθ)) ≤ rtol.

The engine is one compiled step, [`advance`][gimwatch.metrics.tracker.krylov.advance], that asks
its caller for each product (reverse communication, as ARPACK's):
[`leading`][gimwatch.metrics.tracker.krylov.leading] drives it with DeNOC's compiled products
inside one compiled call (no Python per product: ``which`` = 0 for M·x, 1 for (M − σ·1)⁻¹ y on
the factor of `gimwatch.denoc.fused.factor_shifted`), and
[`leading_callable`][gimwatch.metrics.tracker.krylov.leading_callable] with a Python callable (for
other providers). Every matrix-free κ of gimwatch runs on it. Vectors are rows: ``V[j]`` is basis
vector j, contiguous.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gimwatch.denoc import fused
from gimwatch.jit import njit

__all__ = [
    "CHECK_EVERY",
    "MAX_BASIS",
    "STATE_SIZE",
    "Workspace",
    "advance",
    "leading",
    "leading_callable",
]

#: Largest Krylov basis before a thick restart.
MAX_BASIS = 24
#: Products between two Rayleigh–Ritz checks of `leading_callable` (one Python call each).
CHECK_EVERY = 4


class Workspace:
    """Preallocated arrays of `leading` for an operator of size n."""

    def __init__(self, n: int) -> None:
        size = min(MAX_BASIS, n)
        self.V = np.zeros((size, n))
        self.AV = np.zeros((size, n))
        self.H = np.zeros((size, size))
        self.vectors = np.zeros((3, n))  # product output, residual, scratch

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(V, AV, H, vectors), in `leading`'s argument order."""
        return self.V, self.AV, self.H, self.vectors


@njit(cache=True)
def _orthonormalize_into(V, m, x, w):
    """V[m] = x orthogonalised against V[:m] twice (CGS2), normalised; False if in span."""
    n = x.shape[0]
    norm0 = 0.0
    for i in range(n):
        w[i] = x[i]
        norm0 += x[i] * x[i]
    if norm0 == 0.0:
        return False
    for _ in range(2):
        for j in range(m):
            dot = 0.0
            for i in range(n):
                dot += V[j, i] * w[i]
            for i in range(n):
                w[i] -= dot * V[j, i]
    norm = 0.0
    for i in range(n):
        norm += w[i] * w[i]
    if norm <= 1e-24 * norm0:
        return False
    scale = 1.0 / np.sqrt(norm)
    for i in range(n):
        V[m, i] = w[i] * scale
    return True


@njit(cache=True)
def _h_column(V, AV, H, m):
    """Projected matrix column m: H[:m+1, m] = V[:m+1] · A V[m] (and its mirror)."""
    n = V.shape[1]
    for j in range(m + 1):
        dot = 0.0
        for i in range(n):
            dot += V[j, i] * AV[m, i]
        H[j, m] = dot
        H[m, j] = dot


@njit(cache=True)
def _combine(source, vectors, m, col, out):
    """Out = Σ_j vectors[j, col] · source[j] over the first m rows."""
    n = source.shape[1]
    for i in range(n):
        out[i] = 0.0
    for j in range(m):
        s = vectors[j, col]
        for i in range(n):
            out[i] += s * source[j, i]


@njit(cache=True)
def _apply(which, x, out, model):
    """Out = M x (which = 0) or (M − σ·1)⁻¹ x (which = 1) by DeNOC's compiled recursions."""
    index, floating, rot, vec, block, six, scal, root = model
    if which == 0:
        fused.gim_product(x, index, floating, rot, vec, block, six, out)
    else:
        fused.gim_solve(x, index, floating, rot, vec, block, six, scal, root, out)


@njit(cache=True)
def _eigh(H, m):  # noqa: C901, PLR0912  # numba kernel: Jacobi sweeps in one loop nest
    """Eigen-decomposition of the symmetric H[:m, :m], ascending (cyclic Jacobi for m ≤ 12).

    Jacobi rotations until every off-diagonal entry is below 1e-17 of the Frobenius norm —
    as accurate as LAPACK's and, for the few-vector bases of a warm start, several times
    cheaper than a LAPACK call from compiled code. Larger bases go to ``np.linalg.eigh``.
    """
    if m > 12:
        return np.linalg.eigh(H[:m, :m])
    a = H[:m, :m].copy()
    v = np.eye(m)
    norm = 0.0
    for i in range(m):
        for j in range(m):
            norm += a[i, j] * a[i, j]
    threshold = 1e-34 * norm
    for _ in range(60):
        off = 0.0
        for i in range(m):
            for j in range(i + 1, m):
                off += a[i, j] * a[i, j]
        if off <= threshold:
            break
        for p in range(m - 1):
            for r in range(p + 1, m):
                apr = a[p, r]
                if apr == 0.0:
                    continue
                tau = (a[r, r] - a[p, p]) / (2.0 * apr)
                t = (1.0 if tau >= 0 else -1.0) / (abs(tau) + np.sqrt(1.0 + tau * tau))
                c = 1.0 / np.sqrt(1.0 + t * t)
                s = t * c
                for k in range(m):  # columns p, r
                    akp, akr = a[k, p], a[k, r]
                    a[k, p] = c * akp - s * akr
                    a[k, r] = s * akp + c * akr
                for k in range(m):  # rows p, r
                    apk, ark = a[p, k], a[r, k]
                    a[p, k] = c * apk - s * ark
                    a[r, k] = s * apk + c * ark
                for k in range(m):
                    vkp, vkr = v[k, p], v[k, r]
                    v[k, p] = c * vkp - s * vkr
                    v[k, r] = s * vkp + c * vkr
    values = np.empty(m)
    for i in range(m):
        values[i] = a[i, i]
    order = np.argsort(values)
    return values[order], v[:, order]


@njit(cache=True)
def ritz_step(V, AV, H, m, keep, sigma, restart, residual, ritz_out):  # noqa: PLR0913  # numba kernel
    """Rayleigh–Ritz on V[:m]: (θ, error estimate, basis size after an optional restart).

    Writes the residual r = A y − θ y of the leading Ritz pair (θ, y) into ``residual`` and
    the ``keep`` leading Ritz vectors into ``ritz_out`` (leading last). With ``restart``
    the basis is thick-restarted to those vectors: V[:keep] and A V[:keep] become the Ritz
    vectors and their products (combinations of the stored ones) and H their Ritz values.
    """
    n = V.shape[1]
    values, evecs = _eigh(H, m)
    theta = values[m - 1]
    second = values[m - 2] if m >= 2 else 0.0
    for i in range(n):
        residual[i] = 0.0
    for j in range(m):
        s = evecs[j, m - 1]
        for i in range(n):
            residual[i] += s * (AV[j, i] - theta * V[j, i])
    rnorm2 = 0.0
    for i in range(n):
        rnorm2 += residual[i] * residual[i]
    gap = theta - second if m >= 2 else abs(theta)
    estimate = np.inf
    if theta > 0 and gap > 0:
        estimate = rnorm2 / (theta * gap) / (1.0 + sigma * theta)
    if m == n:
        estimate = 0.0
    kept = min(keep, m)
    for k in range(kept):
        _combine(V, evecs, m, m - kept + k, ritz_out[k])
    if restart:
        moved = np.empty((kept, n))
        for k in range(kept):
            _combine(AV, evecs, m, m - kept + k, moved[k])
        H[:, :] = 0.0
        for k in range(kept):
            V[k] = ritz_out[k]
            AV[k] = moved[k]
            H[k, k] = values[m - kept + k]
        m = kept
    return theta, estimate, m


#: The engine's counters between two calls of `advance` (an int64 array of this length):
#: phase (0 fresh, 1 a start vector's product pending, 2 a Lanczos product pending), basis size m,
#: products used, start vectors read, products since the last check, converged (0 / 1).
STATE_SIZE = 6


@njit(cache=True)
def advance(  # noqa: PLR0913  # numba kernel: flat arrays and scalars
    state,
    result,
    starts,
    count,
    sigma,
    rtol,
    budget,
    keep,
    check_every,
    V,
    AV,
    H,
    vectors,
    ritz_out,
):
    """One step of the engine; returns the row m whose product A V[m] it needs next, or −1.

    Reverse communication (as ARPACK's): the caller writes A V[m] into AV[m] and calls again,
    so that the one algorithm serves compiled operators (`leading`) and Python callables
    (`leading_callable`). Start from ``state`` all zero; when it returns −1, ``result`` holds
    (θ, error estimate) and ``state`` the products used (2) and whether it converged (5).
    See `leading` for the other arguments.
    """
    phase, m, used, k, steps = state[0], state[1], state[2], state[3], state[4]
    n, size = V.shape[1], V.shape[0]
    residual, spare = vectors[1], vectors[2]
    if phase != 0:  # the caller wrote A V[m] into AV[m]
        _h_column(V, AV, H, m)
        m, used, steps = m + 1, used + 1, steps + 1
    if phase <= 1:  # the start block: one product per independent start vector
        while k < count:
            k += 1
            if m < size and _orthonormalize_into(V, m, starts[k - 1], spare):
                state[0], state[1], state[2], state[3], state[4] = 1, m, used, k, 0
                return m
    elif not (steps >= check_every or m == size or used >= budget):
        if _orthonormalize_into(V, m, AV[m - 1], spare):  # the Lanczos sequence goes on
            state[0], state[1], state[2], state[4] = 2, m, used, steps
            return m
    restart = m + check_every > size
    theta, estimate, grown = ritz_step(V, AV, H, m, keep, sigma, restart, residual, ritz_out)
    converged = m == n or (theta > 0 and estimate <= rtol)
    result[0], result[1] = theta, estimate
    state[1], state[2], state[5] = grown, used, 1 if converged else 0
    if converged or used >= budget:
        return -1
    if grown >= n or not _orthonormalize_into(V, grown, residual, spare):
        return -1  # the residual lies in the basis
    state[0], state[3], state[4] = 2, k, 0  # Lanczos restarts from the residual
    return grown


@njit(cache=True)
def leading(  # noqa: PLR0913  # numba kernel: flat arrays and scalars
    which, starts, count, sigma, rtol, budget, keep, check_every, V, AV, H, vectors, ritz_out, model
):
    """Leading eigenpair by thick-restart Lanczos from ``starts[:count]`` (module docstring).

    The engine (`advance`) driven by DeNOC's compiled products, inside one compiled call.

    Args:
        which: 0 (M·x) or 1 ((M − σ·1)⁻¹ y) on DeNOC's configured model.
        starts: Start vectors as rows; only the first ``count`` are read.
        count: Number of start vectors.
        sigma: The shift of ``which`` = 1 (0 for ``which`` = 0).
        rtol: Relative tolerance on λ (the stopping rule).
        budget: Most products to spend.
        keep: Ritz vectors to return (and to thick-restart on).
        check_every: Products between two Rayleigh–Ritz checks.
        V: (size, n) basis workspace ([`Workspace`][gimwatch.metrics.tracker.krylov.Workspace]).
        AV: (size, n) products of the basis.
        H: (size, size) projected matrix.
        vectors: (3, n) scratch.
        ritz_out: (≥ keep, n): receives the leading Ritz vectors, leading last.
        model: (index, floating, rot, vec, block, six, scal, root) of the DeNOC products.

    Returns:
        (θ, error estimate of λ (relative), converged, products used).
    """
    state = np.zeros(STATE_SIZE, dtype=np.int64)
    result = np.zeros(2)
    out = vectors[0]
    args = (starts, count, sigma, rtol, budget, keep, check_every, V, AV, H, vectors, ritz_out)
    m = advance(state, result, *args)
    while m >= 0:
        _apply(which, V[m], out, model)
        AV[m] = out
        m = advance(state, result, *args)
    return result[0], result[1], state[5] == 1, state[2]


def leading_callable(
    apply: Callable[[np.ndarray], np.ndarray],
    starts: np.ndarray,
    workspace: Workspace,
    ritz_out: np.ndarray,
    *,
    rtol: float,
    budget: int,
    keep: int,
) -> tuple[float, float, bool, int]:
    """`leading` for an operator given as a Python callable (σ = 0, a check every 4 products).

    The same engine (`advance`), one Python call of ``apply`` per product: for providers
    other than DeNOC's compiled model (Pinocchio's RNEA/ABA, S = D^-1/2 M D^-1/2, test
    operators).
    """
    V, AV, H, vectors = workspace.arrays()
    state = np.zeros(STATE_SIZE, dtype=np.int64)
    result = np.zeros(2)
    starts = np.ascontiguousarray(starts, dtype=float)
    args = (starts, starts.shape[0], 0.0, rtol, budget, keep, CHECK_EVERY, V, AV, H, vectors)
    m = advance(state, result, *args, ritz_out)
    while m >= 0:
        AV[m] = apply(V[m].copy())
        m = advance(state, result, *args, ritz_out)
    return float(result[0]), float(result[1]), bool(state[5] == 1), int(state[2])
