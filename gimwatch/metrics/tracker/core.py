"""κ₂ of M(q) along a trajectory at O(n) per sample: warm-started Krylov on M·x and M⁻¹·y.

Shah & Saha (2013) propose δ and αδ because κ₂ = λmax/λmin (Eq. 6) by a dense eigen-solve
costs O(n³). Along a trajectory M(q) changes little from one sample to the next, and so do
its extreme eigenpairs: the previous sample's are a near-perfect start.
[`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] tracks both ends with O(n) operators and
thick-restart Lanczos ([`gimwatch.metrics.tracker.krylov`][gimwatch.metrics.tracker.krylov]), each
end started from the previous sample's Ritz block plus one fresh seeded random probe (on DeNOC's
model the λmax end starts from its block alone, `denoc.WARM_PROBE`), stopped on
the Kato–Temple estimate ‖r‖²/(θ · gap) ≤ rtol/4 of each end (`STOP`), then **certified**.

* **λmax**: Lanczos on M·x (inverse dynamics from rest).
* **λmin**, on DeNOC's compiled model: shift-invert. The articulated-body factor of
  M − σ·1, σ = λmin(previous) · (1 − s), is one O(n) pass (the shift enters the pivots like a
  negative armature); by Sylvester's law of inertia all its pivots are positive exactly when
  σ < λmin, so an eigenvalue that dropped below σ is detected, not assumed (s is then widened
  and the factor redone; s = 1 is the plain M⁻¹). Lanczos on (M − σ·1)⁻¹ sees λmin as
  θ = 1/(λmin − σ), separated from the next by (λ₂ − σ)/(λmin − σ) — a factor of hundreds
  where λmin and λ₂ of a long chain differ by 0.07 % — and λmin = σ + 1/θ keeps its relative
  accuracy (κ ~ 1e11 at n = 400). s follows the observed motion of λmin (10× the last
  relative change, at least 1e-8).
* **λmin**, on other providers (Pinocchio's ABA, test operators): Lanczos on M⁻¹·y with a
  block of 8 Ritz vectors.

**Both ends are certified at every sample** by Sylvester's law of inertia, at the tolerance:
M − λmax(1 + rtol)·1 must have only negative pivots (no eigenvalue above) and
M − λmin(1 − rtol)·1 only positive ones (no eigenvalue below). Ritz values lie inside the
spectrum (λmax ≥ its Ritz value, λmin ≤ σ + 1/θ), so a passed certificate brackets each end to
rtol whatever Lanczos converged to, and the true κ lies in [κ, κ·(1 + e)], e = 2·rtol/(1 − rtol)
(``error_estimate``). The certificate is what catches eigenvalue crossings: a warm Ritz block
holding the old extreme eigenvector (an exact eigenpair when the crossing mode lives in a
decoupled part of the tree — the other arm of a dual-arm robot, the other branch) converges at
once on the wrong eigenvalue with a tiny residual. On DeNOC's model each certificate is one O(n)
factorization of M − shift·1 (3 per warm sample with the shift-invert one); on
[`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts] it is Pinocchio's
sparse LDLᵀ of CRBA's M with the shift on the diagonal (armature included); on a provider
without ``shifted_inertia(shift)``, Cholesky of ``dense(q)``; without either the sample is
returned with ``certified = False`` and ``error_estimate = inf``.

**A failed certificate recovers the value.** On DeNOC's model: λmax from a cold start (a probe and
the Ritz block), and when that still does not certify, by Sylvester bisection on the shift to
rtol (its bracket is the bound), the block then given the new eigenvector by inverse iteration
just above λmax; λmin likewise (bisection to 1e-3, Lanczos on (M − lo·1)⁻¹, bisection to rtol if
needed). ``fallback = "cold"`` then means recovered and certified. On the other providers a
failed certificate is a dense solve (``"dense"``) of ``dense(q)`` or the provider's
``gim_matrix()``.

**Detected fallback.** An end's warm start has failed when it has not converged within
``warm_products`` products, or when its eigenvalue moved by more than ``jump`` (relative)
since the previous sample; it is then recomputed from a cold start (a new probe and the
best current Ritz vectors, up to ``max_products``) and certified as above. A provider that
cannot converge falls back to the dense matrix when a ``dense`` provider was given, else a
[`ConditioningError`][gimwatch.errors.ConditioningError] is raised. The first sample is a cold
start. Each sample reports the products and factorizations it took
([`TrackedKappa`][gimwatch.metrics.tracker.TrackedKappa]).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import scipy.linalg

from gimwatch.errors import ConditioningError, InputError
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.tracker.denoc import CERTIFY, STOP, DenocEnds
from gimwatch.metrics.tracker.krylov import Workspace, leading_callable

__all__ = ["KappaTracker", "TrackedKappa", "TrackerSettings", "track_kappa"]

_ORDER = ("", "start", "cold")


@dataclass(frozen=True)
class TrackedKappa:
    """κ₂ at one sample, from the tracker.

    Attributes:
        kappa: λmax / λmin.
        lambda_max: Largest eigenvalue of M.
        lambda_min: Smallest eigenvalue of M.
        products: O(n) products this sample took (M·x plus M⁻¹·y or (M − σ·1)⁻¹·y).
        products_max: Of which M·x (the λmax end).
        products_min: Of which solves (the λmin end).
        fallback: ``""`` (warm start sufficed), ``"start"`` (first sample, cold), ``"cold"``
            (warm start failed, recomputed from a cold start) or ``"dense"``.
        error_estimate: Bound on the relative error of κ from the certificates' brackets: the
            true κ lies in [κ, κ·(1 + error_estimate)] (λmax in [λ, λ(1 + b)] and λmin in
            [λ(1 − b), λ], b = rtol each after a passed certificate, the bisection's bracket
            after a recovery); ``n·eps·κ`` after a dense solve (its round-off); ``inf`` when the
            sample is not certified.
        factors: O(n) factorizations this sample took (shift-invert, the two certificates,
            more after a recovery).
        certified: Whether both ends passed their Sylvester certificate (or came from a dense
            solve). False only on a provider that cannot count eigenvalues past a shift and
            without a ``dense`` fallback; the value is then unverified.
    """

    kappa: float
    lambda_max: float
    lambda_min: float
    products: int
    products_max: int
    products_min: int
    fallback: str
    error_estimate: float
    factors: int = 1
    certified: bool = True


class _End:
    """One end of the spectrum on a Python provider: its operator and the Ritz block it keeps."""

    def __init__(self, apply: Callable[[np.ndarray], np.ndarray], n: int, keep: int) -> None:
        self.apply, self.keep = apply, keep
        self.block: np.ndarray | None = None  # rows, leading last
        self.previous: np.ndarray | None = None  # the sample before's leading vector
        self.theta = np.nan
        self.workspace = Workspace(n)


@dataclass(frozen=True)
class TrackerSettings:
    """How hard the κ tracker works and when it gives up a warm start.

    Attributes:
        rtol: Relative tolerance on each extreme eigenvalue, certified (Lanczos stops at
            rtol/4, the certificate holds each end to rtol).
        warm_products: Products per end the warm start may take before it counts as failed.
        max_products: Products per end of the cold start before the dense fallback
            (None: 400 + 4 n).
        jump: Relative change of an extreme eigenvalue since the previous sample beyond which
            the warm result is re-checked by a cold start.
        seed: Seed of the random probe vectors.
        blocks: Ritz vectors carried from sample to sample, (λmax end, 1/λmin end); the
            compiled DeNOC path carries 2 at the λmin end (shift-invert separates it).
    """

    rtol: float = 1e-10
    warm_products: int = 80
    max_products: int | None = None
    jump: float = 0.5
    seed: int = 0
    blocks: tuple[int, int] = (2, 8)


class KappaTracker:
    """Tracks κ₂(M(q)) sample after sample from O(n) products (see the module docstring).

    Args:
        products: An object with ``configure(q)``, ``gim_product(x)`` (M·x) and
            ``gim_solve(y)`` (M⁻¹·y) at the configured q: a
            [`gimwatch.denoc.lean.LeanModel`][gimwatch.denoc.LeanModel] (``DenocModel.lean()``:
            compiled, with shift-invert for λmin), or
            [`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts]. Optional:
            ``shifted_inertia(shift)`` ((positive, negative) pivots of an LDLᵀ of M − shift·1,
            for the certificates; it may return None when it cannot shift) and ``gim_matrix()``
            (dense M, for a recovery).
        nv: Size of M.
        settings: Tolerance, budgets and seed
            ([`TrackerSettings`][gimwatch.metrics.tracker.TrackerSettings]; None: the defaults).
        dense: ``q ↦ M(q)`` for the last fallback and, on providers without
            ``shifted_inertia``, the certificates (None: raise, or leave uncertified).
    """

    def __init__(
        self,
        products,
        nv: int,
        settings: TrackerSettings | None = None,
        *,
        dense: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> None:
        settings = TrackerSettings() if settings is None else settings
        if not (0 < settings.rtol < 1):
            raise InputError("rtol", "between 0 and 1", settings.rtol)
        self.products, self.nv = products, int(nv)
        self.rtol, self.jump = float(settings.rtol), float(settings.jump)
        self.warm_products = int(settings.warm_products)
        self.max_products = int(settings.max_products or 400 + 4 * self.nv)
        self.dense = dense
        self._rng = np.random.default_rng(settings.seed)
        blocks = settings.blocks
        self._denoc = DenocEnds.of(products, self.nv, keep=(blocks[0], 2), seed=settings.seed)
        self._ends = (
            _End(products.gim_product, self.nv, blocks[0]),
            _End(products.gim_solve, self.nv, blocks[1]),
        )

    def eigenvectors(self) -> tuple[np.ndarray, np.ndarray]:
        """The last sample's eigenvectors of λmax and of λmin (unit vectors)."""
        if self._denoc is not None and self._denoc.sampled:
            return self._denoc.eigenvectors()
        top, low = self._ends[0].block, self._ends[1].block
        if top is None or low is None:
            raise ConditioningError("the κ tracker has not sampled yet")
        return top[-1].copy(), low[-1].copy()

    def _probe(self) -> np.ndarray:
        return self._rng.standard_normal(self.nv)

    def sample(self, q: npt.ArrayLike) -> TrackedKappa:
        """κ₂ at configuration ``q``, warm-started from the previous sample.

        Raises:
            ConditioningError: M(q) is not positive definite, or no method converged.
        """
        q = np.asarray(q, dtype=float)
        try:
            certified: bool | None
            if self._denoc is not None:
                ends = self._denoc.sample(q, self)
                factors, certified = ends.pop(), True
            else:
                self.products.configure(q)
                ends = [self._end(end) for end in self._ends]
                factors, certified = self._certify(q, ends[0][0], ends[1][0])
                if not certified:
                    matrix = self._matrix(q)
                    if matrix is not None:
                        return self._dense_sample(matrix)
        except ConditioningError:
            if self.dense is None:
                raise
            return self._dense_sample(self.dense(q))
        (top, n_max, fb_max, b_max), (low, n_min, fb_min, b_min) = ends
        if not (top > 0 and low > 0):
            raise ConditioningError(
                f"M(q) must be positive definite, got λmax = {top:.6g}, λmin = {low:.6g}"
            )
        bound = (b_max + b_min) / (1.0 - b_min) if certified else np.inf  # (1+a)/(1-b) - 1
        return TrackedKappa(
            kappa=float(top / low),
            lambda_max=float(top),
            lambda_min=float(low),
            products=n_max + n_min,
            products_max=n_max,
            products_min=n_min,
            fallback=max(fb_max, fb_min, key=_ORDER.index),
            error_estimate=float(bound),
            factors=factors,
            certified=bool(certified),
        )

    def _certify(self, q: np.ndarray, top: float, low: float) -> tuple[int, bool | None]:
        """(factorizations, certified) of a Python provider's ends; certified None: cannot.

        λmax passes when M − λmax(1 + CERTIFY·rtol)·1 has no positive eigenvalue, λmin when
        M − λmin(1 − CERTIFY·rtol)·1 has no negative one (Sylvester's law of inertia): from the
        provider's ``shifted_inertia(shift)`` ((positive, negative) pivots of its factor of
        M − shift·1, O(n)-ish on Pinocchio's sparse LDLᵀ), else from Cholesky of the dense M.
        """
        margin = CERTIFY * self.rtol
        above, below = top * (1.0 + margin), low * (1.0 - margin)
        inertia = getattr(self.products, "shifted_inertia", None)
        counts = None if inertia is None else inertia(above)
        if inertia is not None and counts is not None:  # a provider may decline (None)
            return 2, counts[1] == self.nv and inertia(below)[0] == self.nv
        if self.dense is None:
            return 0, None
        M = self.dense(q)
        shifted = (above * np.eye(self.nv) - M, M - below * np.eye(self.nv))
        return 2, all(scipy.linalg.lapack.dpotrf(A, lower=1)[1] == 0 for A in shifted)

    def _matrix(self, q: np.ndarray) -> np.ndarray | None:
        """The dense M(q) for a recovery: ``dense``'s, else the provider's, else None."""
        if self.dense is not None:
            return self.dense(q)
        gim_matrix = getattr(self.products, "gim_matrix", None)
        return None if gim_matrix is None else gim_matrix()

    def _leading(self, end: _End, starts: list[np.ndarray], budget: int):
        block = np.empty((end.keep, self.nv))
        theta, estimate, ok, used = leading_callable(
            end.apply,
            np.array(starts),
            end.workspace,
            block,
            rtol=self.rtol * STOP,
            budget=budget,
            keep=end.keep,
        )
        return theta, block[: min(end.keep, used)], estimate, ok, used

    def _end(self, end: _End) -> tuple[float, int, str, float]:
        """(λ, products, fallback, estimate) of one end on a Python provider."""
        fallback, result, count = "", None, 0
        if end.block is not None:
            # the last two leading vectors span the extrapolation of the eigenvector's motion
            extra = [] if end.previous is None else [end.previous]
            theta, block, estimate, ok, used = self._leading(
                end, [*end.block, *extra, self._probe()], self.warm_products
            )
            count += used
            moved = abs(theta - end.theta) > self.jump * abs(end.theta)
            if ok and not moved:
                result = (theta, block, estimate)
            else:
                fallback, end.block = "cold", block
        else:
            fallback = "start"
        if result is None:
            starts = [self._probe(), *([] if end.block is None else end.block)]
            theta, block, estimate, ok, used = self._leading(end, starts, self.max_products)
            count += used
            if ok:
                result = (theta, block, estimate)
        if result is None:
            raise ConditioningError(
                f"the κ tracker did not converge in {self.max_products} products "
                "and has no dense fallback"
            )
        end.previous = None if end.block is None else end.block[-1].copy()
        end.theta, end.block = result[0], result[1]
        value = result[0] if end is self._ends[0] else 1.0 / result[0]
        return value, count, fallback, CERTIFY * self.rtol

    def _dense_sample(self, matrix: np.ndarray) -> TrackedKappa:
        values, vectors = scipy.linalg.eigh(matrix, check_finite=False)
        if values[0] <= 0:
            raise ConditioningError(f"M(q) must be positive definite, got λmin = {values[0]:.6g}")
        top, low = vectors[:, -2:].T, vectors[:, :2][:, ::-1].T
        self._ends[0].theta, self._ends[0].block = float(values[-1]), top
        self._ends[1].theta, self._ends[1].block = float(1.0 / values[0]), low
        if self._denoc is not None:
            self._denoc.restart(values[-1], values[0], top, low)
        kappa = extreme_ratio(values)
        return TrackedKappa(
            kappa=kappa,
            lambda_max=float(values[-1]),
            lambda_min=float(values[0]),
            products=0,
            products_max=0,
            products_min=0,
            fallback="dense",
            error_estimate=float(self.nv * np.finfo(float).eps * kappa),
            factors=0,
        )


def track_kappa(
    products, configurations: npt.ArrayLike, settings: TrackerSettings | None = None
) -> list[TrackedKappa]:
    """κ₂ at every configuration (rows of ``configurations``), in order, warm-started.

    Args:
        products: See [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker].
        configurations: (samples, nq).
        settings: See [`TrackerSettings`][gimwatch.metrics.tracker.TrackerSettings].
    """
    qs = np.atleast_2d(np.asarray(configurations, dtype=float))
    tracker = KappaTracker(products, products.nv, settings)
    return [tracker.sample(q) for q in qs]
