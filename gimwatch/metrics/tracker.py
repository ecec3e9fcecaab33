"""κ₂ of M(q) along a trajectory at O(n) per sample: warm-started Krylov on M·x and M⁻¹·y.

Shah & Saha (2013) propose δ and αδ because κ₂ = λmax/λmin (Eq. 6) by a dense eigen-solve
costs O(n³). Along a trajectory M(q) changes little from one sample to the next, and so do
its extreme eigenvectors: the previous sample's are a near-perfect start. :class:`KappaTracker`
tracks both ends with the O(n) products gimwatch already has — M·x (inverse dynamics from
rest) for λmax and M⁻¹·y (the articulated-body solve) for 1/λmin, which keeps λmin's relative
accuracy even when κ nears 1/eps, where a dense solver no longer resolves it.

Method, per end and per sample (thick-restart Lanczos with full reorthogonalisation, started
from a block — the warm start — with Rayleigh–Ritz on the whole basis):

1. **Warm start.** The basis starts with the previous sample's leading Ritz vectors (2 for
   λmax; 8 for 1/λmin, because the smallest eigenvalues of a long chain's M cluster — at
   n = 200 the two largest of M⁻¹ differ by 0.07 % — and Rayleigh–Ritz on the tracked
   cluster resolves crossings inside it exactly) and one fresh seeded random probe vector
   (it has a component on every eigenvector, so a new leading eigenvector that appeared
   orthogonally to the block keeps the residual large until the basis has found it).
2. **Expansion.** Lanczos steps (each new vector A times the previous one, orthogonalised
   twice against the basis); every 4 products, Rayleigh–Ritz gives the leading Ritz pair
   (θ, y), its residual r = A y − θ y restarts the Lanczos sequence; a full basis (24) is
   thick-restarted on the leading Ritz vectors.
3. **Stopping rule (the stated tolerance).** Converged when ‖r‖² / (θ · gap) ≤ rtol, with
   gap = θ − θ₂ from the Ritz values: the Kato–Temple bound on the relative error of θ.
   Both ends at rtol give κ to about 2·rtol (default rtol = 1e-10).
4. **Detected fallback.** The warm start has failed when it has not converged within
   ``warm_products`` products, or when θ moved by more than ``jump`` (relative) since the
   previous sample (an eigenvalue crossing from below or a sudden change of the model);
   the end is then recomputed from a cold start (a new random probe and the best current
   Ritz vectors, up to ``max_products``) and, if that does not converge either, from the
   dense matrix when a ``dense`` provider was given, else a
   :class:`~gimwatch.errors.ConditioningError` is raised. The first sample is a cold start.

Each sample reports how many products it took (:class:`TrackedKappa`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg
from numba import njit

from gimwatch.denoc import fused
from gimwatch.errors import ConditioningError, InputError

__all__ = ["KappaTracker", "TrackedKappa", "track_kappa"]

_MAX_BASIS = 24
_BLOCK = 2


@dataclass(frozen=True)
class TrackedKappa:
    """κ₂ at one sample, from the tracker.

    Attributes:
        kappa: λmax / λmin.
        lambda_max: Largest eigenvalue of M.
        lambda_min: Smallest eigenvalue of M.
        products: O(n) products this sample took (M·x plus M⁻¹·y).
        products_max: Of which M·x (the λmax end).
        products_min: Of which M⁻¹·y (the λmin end).
        fallback: ``""`` (warm start sufficed), ``"start"`` (first sample, cold), ``"cold"``
            (warm start failed, recomputed from a cold start) or ``"dense"``.
        error_estimate: Estimated relative error of κ (sum of both ends' ‖r‖²/(θ·gap)).
    """

    kappa: float
    lambda_max: float
    lambda_min: float
    products: int
    products_max: int
    products_min: int
    fallback: str
    error_estimate: float


class _Operator:
    """One end: the symmetric operator x ↦ A x and the Ritz block it carries over."""

    def __init__(
        self, apply: Callable[[np.ndarray], np.ndarray], n: int, keep: int = 2, which: int = 0
    ) -> None:
        self.apply, self.n, self.keep, self.which = apply, n, keep, which
        self.block: np.ndarray | None = None
        self.previous: np.ndarray | None = None  # the sample before's leading vector
        self.theta = math.nan
        self.count = 0


@njit(cache=True)
def _orthonormalize_into(V, m, x):
    """V[:, m] = x orthogonalised against V[:, :m] twice (CGS2), normalised; False if in span."""
    n = V.shape[0]
    norm0 = np.sqrt(np.sum(x * x))
    if norm0 == 0.0:
        return False
    w = x.copy()
    for _ in range(2):
        for j in range(m):
            dot = 0.0
            for i in range(n):
                dot += V[i, j] * w[i]
            for i in range(n):
                w[i] -= dot * V[i, j]
    norm = np.sqrt(np.sum(w * w))
    if norm <= 1e-12 * norm0:
        return False
    for i in range(n):
        V[i, m] = w[i] / norm
    return True


@njit(cache=True)
def _h_column(V, AV, H, m):
    """Projected matrix column m: H[:m+1, m] = V[:, :m+1]ᵀ A V[:, m] (and its mirror)."""
    n = V.shape[0]
    for j in range(m + 1):
        dot = 0.0
        for i in range(n):
            dot += V[i, j] * AV[i, m]
        H[j, m] = dot
        H[m, j] = dot


@njit(cache=True)
def _lanczos_next(V, AV, H, m):
    """Fill H's column m; put A v_m, orthonormalised, into V[:, m + 1] (False: no room/in span)."""
    _h_column(V, AV, H, m)
    if m + 1 >= V.shape[1]:
        return False
    return _orthonormalize_into(V, m + 1, AV[:, m])


@njit(cache=True)
def _ritz(V, AV, H, m, keep, block, restart):
    """Rayleigh–Ritz on V[:, :m]: (θ, ‖r‖, θ₂, new size) of the leading Ritz pair.

    ``block`` receives the ``keep`` leading Ritz vectors. The residual r = A y − θ y of the
    leading one is orthonormalised into the basis as its next vector; with ``restart`` the
    basis is first thick-restarted to the ``keep`` Ritz vectors (exactly: their products
    are combinations of the stored ones, no product is spent).
    """
    n = V.shape[0]
    values, vectors = np.linalg.eigh(H[:m, :m])
    theta = values[m - 1]
    second = values[m - 2] if m >= 2 else 0.0
    residual = np.zeros(n)
    for j in range(m):
        s = vectors[j, m - 1]
        for i in range(n):
            residual[i] += s * (AV[i, j] - theta * V[i, j])
    rnorm = np.sqrt(np.sum(residual * residual))
    block[:, :] = 0.0
    for k in range(keep):
        col = m - keep + k
        for j in range(m):
            s = vectors[j, col]
            for i in range(n):
                block[i, k] += s * V[i, j]
    if restart:
        moved = np.zeros((n, keep))
        for k in range(keep):
            col = m - keep + k
            for j in range(m):
                s = vectors[j, col]
                for i in range(n):
                    moved[i, k] += s * AV[i, j]
        for k in range(keep):
            V[:, k] = block[:, k]
            AV[:, k] = moved[:, k]
        H[:, :] = 0.0
        for k in range(keep):
            H[k, k] = values[m - keep + k]
        m = keep
    grown = m + 1 if m < n and _orthonormalize_into(V, m, residual) else m
    return theta, rnorm, second, grown


def _leading(
    end: _Operator,
    starts: list[np.ndarray],
    *,
    rtol: float,
    budget: int,
    keep_block: int = _BLOCK,
    check_every: int = 4,
) -> tuple[float, np.ndarray, float, bool]:
    """Leading eigenpair by thick-restart Lanczos from ``starts``, at most ``budget`` products.

    The basis grows Lanczos-style (each new vector is A times the previous one,
    orthogonalised against the basis twice); Rayleigh–Ritz and the stopping rule run every
    ``check_every`` products, and its residual restarts the Lanczos sequence.

    Returns:
        (θ, the top Ritz vectors as columns, error estimate, converged).
    """
    n = end.n
    size = min(_MAX_BASIS, n)
    V = np.empty((n, size), order="F")  # columns contiguous
    AV = np.empty((n, size), order="F")
    H = np.zeros((size, size))
    m = used = 0
    for vector in starts:
        if m < size and _orthonormalize_into(V, m, np.ascontiguousarray(vector)):
            AV[:, m] = end.apply(V[:, m])
            _h_column(V, AV, H, m)
            m, used = m + 1, used + 1
    while True:
        keep = min(keep_block, m)
        block = np.empty((n, keep))
        restart = m + check_every > size
        theta, rnorm, second, grown = _ritz(V, AV, H, m, keep, block, restart)
        gap = theta - second if m >= 2 else abs(theta)
        estimate = rnorm * rnorm / (theta * gap) if theta > 0 and gap > 0 else math.inf
        converged = m == n or (theta > 0 and estimate <= rtol)
        stuck = grown == (keep if restart else m)  # the residual lies in the basis
        if converged or used >= budget or stuck:
            return theta, block, (0.0 if m == n else estimate), converged
        m = grown - 1
        for _ in range(check_every):
            AV[:, m] = end.apply(V[:, m])
            used += 1
            more = _lanczos_next(V, AV, H, m)  # H column m, and V[:, m + 1] from A v_m
            m += 1
            if not more or m == size or used >= budget:
                break


@njit(cache=True)
def _apply_lean(which, x, out, index, floating, rot, vec, block, six, scal, root):
    """Write M x (which = 0) or M⁻¹ x (which = 1) into out, by DeNOC's compiled recursions."""
    if which == 0:
        fused.gim_product(x, index, floating, rot, vec, block, six, out)
    else:
        fused.gim_solve(x, index, floating, rot, vec, block, six, scal, root, out)


@njit(cache=True)
def _leading_lean(
    which,
    starts,
    rtol,
    budget,
    keep_block,
    check_every,
    index,
    floating,
    rot,
    vec,
    block,
    six,
    scal,
    root,
):
    """:func:`_leading` compiled whole, on DeNOC's products: no Python per product.

    Returns:
        (θ, the top Ritz vectors as columns, error estimate, converged, products used).
    """
    n = starts.shape[1]
    size = min(_MAX_BASIS, n)
    V = np.empty((size, n)).T  # columns contiguous
    AV = np.empty((size, n)).T
    H = np.zeros((size, size))
    out = np.empty(n)
    m = used = 0
    for k in range(starts.shape[0]):
        if m < size and _orthonormalize_into(V, m, starts[k].copy()):
            _apply_lean(which, V[:, m], out, index, floating, rot, vec, block, six, scal, root)
            AV[:, m] = out
            _h_column(V, AV, H, m)
            m += 1
            used += 1
    while True:
        keep = min(keep_block, m)
        ritz = np.empty((n, keep))
        restart = m + check_every > size
        theta, rnorm, second, grown = _ritz(V, AV, H, m, keep, ritz, restart)
        gap = theta - second if m >= 2 else abs(theta)
        estimate = rnorm * rnorm / (theta * gap) if theta > 0 and gap > 0 else np.inf
        converged = m == n or (theta > 0 and estimate <= rtol)
        stuck = grown == (keep if restart else m)
        if converged or used >= budget or stuck:
            return theta, ritz, (0.0 if m == n else estimate), converged, used
        m = grown - 1
        for _ in range(check_every):
            _apply_lean(which, V[:, m], out, index, floating, rot, vec, block, six, scal, root)
            AV[:, m] = out
            used += 1
            more = _lanczos_next(V, AV, H, m)
            m += 1
            if not more or m == size or used >= budget:
                break


class KappaTracker:
    """Tracks κ₂(M(q)) sample after sample from O(n) products (see the module docstring).

    Args:
        products: An object with ``configure(q)``, ``gim_product(x)`` (M·x) and
            ``gim_solve(y)`` (M⁻¹·y) at the configured q: a
            :class:`gimwatch.denoc.lean.LeanModel` (``DenocModel.lean()``), or
            :class:`gimwatch.metrics.tracker_providers.PinocchioProducts`.
        nv: Size of M.
        rtol: Relative tolerance on each extreme eigenvalue (stopping rule 3).
        warm_products: Products per end the warm start may take before it counts as failed.
        max_products: Products per end of the cold start before the dense fallback.
        jump: Relative change of an extreme eigenvalue since the previous sample beyond which
            the warm result is re-checked by a cold start.
        seed: Seed of the random probe vectors.
        dense: ``q ↦ M(q)`` for the last fallback (None: raise instead).
        blocks: Ritz vectors carried from sample to sample, (λmax end, 1/λmin end).
    """

    def __init__(
        self,
        products,
        nv: int,
        *,
        rtol: float = 1e-10,
        warm_products: int = 80,
        max_products: int | None = None,
        jump: float = 0.5,
        seed: int = 0,
        dense: Callable[[np.ndarray], np.ndarray] | None = None,
        blocks: tuple[int, int] = (2, 8),
    ) -> None:
        if not (0 < rtol < 1):
            raise InputError("rtol", "between 0 and 1", rtol)
        self.products, self.nv = products, int(nv)
        self.rtol, self.warm_products, self.jump = float(rtol), int(warm_products), float(jump)
        self.max_products = int(max_products) if max_products else 400 + 4 * self.nv
        self.dense = dense
        self._rng = np.random.default_rng(seed)
        self._ends = (
            _Operator(products.gim_product, self.nv, blocks[0]),
            _Operator(products.gim_solve, self.nv, blocks[1], 1),
        )
        # DeNOC's products: the whole Krylov loop runs compiled, calling them directly
        arguments = getattr(products, "compiled_operator_arguments", None)
        self._compiled = arguments() if arguments is not None else None

    def eigenvectors(self) -> tuple[np.ndarray, np.ndarray]:
        """The last sample's eigenvectors of λmax and of λmin (unit vectors)."""
        if self._ends[0].block is None:
            raise ConditioningError("the κ tracker has not sampled yet")
        return self._ends[0].block[:, -1].copy(), self._ends[1].block[:, -1].copy()

    def _probe(self) -> np.ndarray:
        return self._rng.standard_normal(self.nv)

    def _end(self, end: _Operator) -> tuple[float, int, str, float]:
        """(θ, products, fallback, estimate) of one end at the configured q."""
        before = end.count
        counting = end.apply

        def apply(x: np.ndarray) -> np.ndarray:
            end.count += 1
            return counting(x)

        counted = _Operator(apply, end.n, end.keep)

        def leading(starts: list[np.ndarray], budget: int):
            if self._compiled is None:
                return _leading(counted, starts, rtol=self.rtol, budget=budget, keep_block=end.keep)
            theta, block, estimate, ok, used = _leading_lean(
                end.which, np.array(starts), self.rtol, budget, end.keep, 4, *self._compiled
            )
            end.count += used
            return float(theta), block, float(estimate), bool(ok)

        fallback = ""
        result = None
        if end.block is not None:
            # the last two leading vectors span the extrapolation of the eigenvector's motion
            extra = [] if end.previous is None else [end.previous]
            starts = [*end.block.T, *extra, self._probe()]
            theta, block, estimate, ok = leading(starts, self.warm_products)
            moved = abs(theta - end.theta) > self.jump * abs(end.theta)
            if ok and not moved:
                result = (theta, block, estimate)
            else:
                fallback, end.block = "cold", block
        else:
            fallback = "start"
        if result is None:
            starts = [self._probe(), *([] if end.block is None else end.block.T)]
            theta, block, estimate, ok = leading(starts, self.max_products)
            if ok:
                result = (theta, block, estimate)
        if result is None:
            raise ConditioningError(
                f"the κ tracker did not converge in {self.max_products} products "
                "and has no dense fallback"
            )
        end.previous = None if end.block is None else end.block[:, -1].copy()
        end.theta, end.block = result[0], result[1]
        return result[0], end.count - before, fallback, result[2]

    def sample(self, q: npt.ArrayLike) -> TrackedKappa:
        """κ₂ at configuration ``q``, warm-started from the previous sample.

        Raises:
            ConditioningError: M(q) is not positive definite, or no method converged.
        """
        q = np.asarray(q, dtype=float)
        self.products.configure(q)
        try:
            top, n_max, fb_max, e_max = self._end(self._ends[0])
            inv, n_min, fb_min, e_min = self._end(self._ends[1])
        except ConditioningError:
            if self.dense is None:
                raise
            return self._dense_sample(q)
        if not (top > 0 and inv > 0):
            raise ConditioningError(
                f"M(q) must be positive definite, got λmax = {top:.6g}, 1/λmin = {inv:.6g}"
            )
        order = ("", "start", "cold")
        fallback = max(fb_max, fb_min, key=order.index)
        return TrackedKappa(
            kappa=float(top * inv),
            lambda_max=float(top),
            lambda_min=float(1.0 / inv),
            products=n_max + n_min,
            products_max=n_max,
            products_min=n_min,
            fallback=fallback,
            error_estimate=float(e_max + e_min),
        )

    def _dense_sample(self, q: np.ndarray) -> TrackedKappa:
        values, vectors = scipy.linalg.eigh(self.dense(q), check_finite=False)
        if values[0] <= 0:
            raise ConditioningError(f"M(q) must be positive definite, got λmin = {values[0]:.6g}")
        for end, theta, block in (
            (self._ends[0], values[-1], vectors[:, -_BLOCK:]),
            (self._ends[1], 1.0 / values[0], vectors[:, :_BLOCK][:, ::-1]),
        ):
            end.theta, end.block = float(theta), block
        return TrackedKappa(
            kappa=float(values[-1] / values[0]),
            lambda_max=float(values[-1]),
            lambda_min=float(values[0]),
            products=0,
            products_max=0,
            products_min=0,
            fallback="dense",
            error_estimate=0.0,
        )


def track_kappa(products, configurations: npt.ArrayLike, **options) -> list[TrackedKappa]:
    """κ₂ at every configuration (rows of ``configurations``), in order, warm-started.

    Args:
        products: See :class:`KappaTracker`.
        configurations: (samples, nq).
        **options: Passed to :class:`KappaTracker`.
    """
    qs = np.atleast_2d(np.asarray(configurations, dtype=float))
    tracker = KappaTracker(products, products.nv, **options)
    return [tracker.sample(q) for q in qs]
