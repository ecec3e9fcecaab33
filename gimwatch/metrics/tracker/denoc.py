"""The κ tracker on DeNOC's compiled model: one compiled call per warm sample, shift-invert λmin.

[`DenocEnds`][gimwatch.metrics.tracker.denoc.DenocEnds] holds the tracker's own DeNOC buffers (the
LeanModel it was given keeps its configuration) and the state carried from sample to sample: each
end's Ritz block, the last λmin and its last relative change. A warm sample is ONE compiled call,
[`warm_sample`][gimwatch.metrics.tracker.denoc.warm_sample]: kinematics at q (Shah & Saha's DeNOC,
`gimwatch.denoc.fused`), Lanczos on M·x for λmax, the articulated factor of M − σ·1 with σ =
λmin(previous)·(1 − s) (refactored with s × 100 while a pivot is not positive — Sylvester's law of
inertia: then λmin ≤ σ — up to s = 1, the plain M⁻¹), and Lanczos on (M − σ·1)⁻¹ for λmin = σ + 1/θ.
Cold starts (the first sample, and the detected failures of a warm one) run the same
compiled pieces from Python: λmin first to 1e-7 on M⁻¹, then shift-invert to the tolerance.
See [`core`][gimwatch.metrics.tracker.core] for the method and its stopping rule.
"""

from __future__ import annotations

import numpy as np

from gimwatch.denoc import fused
from gimwatch.errors import ConditioningError
from gimwatch.jit import njit
from gimwatch.metrics.tracker.krylov import Workspace, leading

__all__ = ["DenocEnds", "warm_sample"]

_CHECK_EVERY = 1  # products between Rayleigh–Ritz checks (a check costs far less than a product)
_MARGIN = 10.0  # s = _MARGIN × the last relative change of λmin
_SHIFT_MIN = 1e-8  # smallest relative shift margin s: above λmin's own tolerance
_ROUND = 12  # products per round of the cold start's shift refinement
_APPROACH = 0.1  # each round moves σ to λ − 0.1 (λ − σ), λ the round's Ritz estimate
_PROBES = 16  # seeded probe vectors, used in turn
#: λmin is certified at every sample: M − λ(1 − CERTIFY·rtol)·1 must factor with positive
#: pivots (Sylvester: no eigenvalue below that shift). Ritz values lie above λmin, so the
#: reported λ is then within CERTIFY·rtol of λmin (relative), whatever Lanczos converged to.
CERTIFY = 100.0


@njit(cache=True)
def _factor_with_margin(low, s, model):
    """Factor M − σ·1, σ = low·(1 − s), widening s × 100 until every pivot is positive.

    Returns (σ, factorizations, positive definite); s ≥ 1 is σ = 0 (the plain factor).
    """
    index, floating, rot, vec, block, six, scal, root = model
    factors = 0
    while True:
        sigma = low * (1.0 - s) if s < 1.0 else 0.0
        factors += 1
        ok = fused.factor_shifted(sigma, index, floating, rot, vec, block, six, scal, root)
        if ok or sigma == 0.0:
            return sigma, factors, ok
        s = min(100.0 * s, 1.0)


@njit(cache=True)
def warm_sample(
    q, geometry, model, starts_max, starts_min, probes, state, params, V, AV, H, vectors, stats
):
    """One warm sample in one call (see `DenocEnds.sample` for ``stats``).

    Args:
        q: Configuration (Pinocchio's order).
        geometry: The packed tree
            ([`compiled_model_arguments`][gimwatch.denoc.LeanModel.compiled_model_arguments]).
        model: (index, floating, rot, vec, block, six, scal, root): the tracker's buffers.
        starts_max: The λmax end's Ritz block (rows, leading last) and a probe row; the block
            is overwritten with the new Ritz vectors.
        starts_min: The same for the λmin end.
        probes: Seeded probe vectors, used in turn.
        state: [λmax, λmin, last relative change of λmin, probes used], updated in place when
            both ends succeed.
        params: [rtol, warm product budget, jump].
        V: Krylov workspace ([`Workspace`][gimwatch.metrics.tracker.krylov.Workspace]), with AV,
            H and vectors.
        AV: See V.
        H: See V.
        vectors: See V.
        stats: Receives the results
            ([`DenocEnds.sample`][gimwatch.metrics.tracker.denoc.DenocEnds.sample]).
    """
    rtol, budget, jump = params[0], int(params[1]), params[2]
    used = int(state[3])
    starts_max[-1] = probes[used % probes.shape[0]]
    starts_min[-1] = probes[(used + 1) % probes.shape[0]]
    state[3] = used + 2
    index, floating, rot, vec, block = model[0], model[1], model[2], model[3], model[4]
    fused.kinematics(q, index, geometry, floating, rot, vec, block)
    keep = starts_max.shape[0] - 1
    top, e_top, ok_top, n_top = leading(
        0, starts_max, keep + 1, 0.0, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_max, model,
    )  # fmt: skip
    s = max(_MARGIN * state[2], _SHIFT_MIN)
    sigma, factors, definite = _factor_with_margin(state[1], s, model)
    stats[:] = 0.0
    stats[0], stats[1], stats[2], stats[3] = top, e_top, ok_top, n_top
    stats[8], stats[9], stats[10] = sigma, factors, definite
    cold_top = not ok_top or abs(top - state[0]) > jump * state[0]
    stats[12] = cold_top
    if not definite:
        stats[11] = 1.0
        return
    keep = starts_min.shape[0] - 1
    theta, e_low, ok_low, n_low = leading(
        1, starts_min, keep + 1, sigma, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_min, model,
    )  # fmt: skip
    low = sigma + 1.0 / theta
    stats[4], stats[5], stats[6], stats[7] = low, e_low, ok_low, n_low
    cold_low = not ok_low or abs(low - state[1]) > jump * state[1]
    stats[13] = cold_low
    stats[11] = cold_top or cold_low
    if not stats[11]:
        state[2] = abs(low - state[1]) / low
        state[0], state[1] = top, low


class DenocEnds:
    """Both ends of the κ tracker on a [`LeanModel`][gimwatch.denoc.LeanModel].

    Args:
        lean: DeNOC's compiled model.
        n: Size of M.
        keep: Ritz vectors carried over, (λmax end, λmin end).
        seed: Seed of the probe vectors.
    """

    def __init__(self, lean, n: int, keep: tuple[int, int], seed: int = 0) -> None:
        index, self._geometry, floating = lean.compiled_model_arguments()
        self._model = (index, floating, *lean.new_workspace())
        self.n = n
        self._starts = [np.zeros((k + 1, n)) for k in keep]
        self._work = Workspace(n)
        self._stats = np.zeros(14)
        self._probes = np.random.default_rng(seed + 1).standard_normal((_PROBES, n))
        self._state = np.zeros(4)  # λmax, λmin, relative change of λmin, probes used
        self.sampled = False

    @classmethod
    def of(cls, products, n: int, keep: tuple[int, int]) -> DenocEnds | None:
        """The compiled ends for DeNOC's LeanModel; None for any other provider."""
        if not hasattr(products, "compiled_model_arguments"):
            return None
        return cls(products, n, keep)

    def eigenvectors(self) -> tuple[np.ndarray, np.ndarray]:
        """The last sample's eigenvectors of λmax and of λmin."""
        return self._starts[0][-2].copy(), self._starts[1][-2].copy()

    def restart(self, top: float, low: float, top_block, low_block) -> None:
        """Carry over a dense solve's eigenpairs (rows, leading last)."""
        for starts, rows in zip(self._starts, (top_block, low_block), strict=True):
            keep = starts.shape[0] - 1
            starts[:keep] = rows[-keep:]
        self._state[:3] = top, low, 0.0
        self.sampled = True

    def _probe(self) -> np.ndarray:
        probe = self._probes[int(self._state[3]) % _PROBES]
        self._state[3] += 1
        return probe

    def _leading(self, which, starts, sigma, rtol, budget, end):
        keep = self._starts[end].shape[0] - 1
        return leading(
            which, starts, starts.shape[0], sigma, rtol, budget, keep, _CHECK_EVERY,
            *self._work.arrays(), self._starts[end], self._model,
        )  # fmt: skip

    def _cold(self, end: int, sigma: float, rtol: float, budget: int):
        """(θ, estimate, converged, products) from a probe and the current Ritz block."""
        block = self._starts[end][:-1]
        starts = np.vstack([self._probe(), block]) if self.sampled else self._probe()[None]
        return self._leading(end, starts, sigma, rtol, budget, end)

    def _cold_low(self, tracker) -> tuple[float, float, bool, int, int]:
        """λmin from a cold start, by shift-invert with a shift refined round after round.

        Round k runs `_ROUND` products of Lanczos on (M − σ·1)⁻¹ from the current Ritz
        block and a probe; its Ritz value gives λ = σ + 1/θ ≥ λmin (θ ≤ the largest
        eigenvalue of the operator). The next shift is λ − 0.1 (λ − σ); when a pivot of
        M − σ·1 is not positive, λmin < σ (Sylvester), and σ is halved back towards the last
        shift that factored. As σ nears λmin, λmin's eigenvalue of (M − σ·1)⁻¹ separates from
        the cluster above it and the rounds converge to the tolerance.
        """
        if not fused.factor_shifted(0.0, *self._model):
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        sigma, factors, used = 0.0, 1, 0
        starts = np.vstack([self._probe(), self._starts[1][:-1]]) if self.sampled else None
        if starts is None:
            starts = self._probe()[None]
        while True:
            budget = min(_ROUND, tracker.max_products - used)
            theta, estimate, ok, spent = self._leading(1, starts, sigma, tracker.rtol, budget, 1)
            used += spent
            low = sigma + 1.0 / theta
            if ok or used >= tracker.max_products:
                return low, estimate, ok, used, factors
            safe, trial = sigma, low - _APPROACH * (low - sigma)
            while trial - safe > 1e-3 * (low - safe):
                factors += 1
                if fused.factor_shifted(trial, *self._model):
                    break
                trial = 0.5 * (safe + trial)
            else:
                factors += 1
                fused.factor_shifted(safe, *self._model)
                trial = safe
            sigma = trial
            starts = np.vstack([self._probe(), self._starts[1][:-1]])

    def _certified(self, low: float, tracker) -> bool:
        """Whether no eigenvalue of M lies below low·(1 − CERTIFY·rtol) (one O(n) factor)."""
        return bool(fused.factor_shifted(low * (1.0 - CERTIFY * tracker.rtol), *self._model))

    def _certified_cold_low(self, tracker) -> tuple[float, float, int, int]:
        """λmin from a cold start, certified; (λmin, estimate, products, factorizations).

        Raises:
            ConditioningError: It did not converge, or an eigenvalue lies below it still
                (the tracker then uses its dense fallback when it has one).
        """
        low, estimate, ok, used, factors = self._cold_low(tracker)
        if not ok:
            raise ConditioningError(f"λmin did not converge in {tracker.max_products} products")
        factors += 1
        if self._certified(low, tracker):
            return low, estimate, used, factors
        return self._bisected_low(low * (1.0 - CERTIFY * tracker.rtol), tracker, used, factors)

    def _bisected_low(self, upper: float, tracker, used: int, factors: int):
        """λmin below ``upper`` by Sylvester bisection, then Lanczos just below it.

        The Ritz block and the probes may all miss the lowest mode (a crossing with a mode
        localised elsewhere in the tree): pivot signs cannot. Bisection on the shift brackets
        λmin in [lo, hi) to 1e-3 relative (a positive factor at lo, not at hi); Lanczos on
        (M − lo·1)⁻¹, where λmin now dominates, gives it and its eigenvector for the next
        warm start. Should that still not certify, the bisection goes on to the tolerance.
        """
        lo, hi, margin = 0.0, upper, CERTIFY * tracker.rtol
        while hi - lo > 1e-3 * hi:
            mid, factors = 0.5 * (lo + hi), factors + 1
            lo, hi = (mid, hi) if fused.factor_shifted(mid, *self._model) else (lo, mid)
        fused.factor_shifted(lo, *self._model)
        starts = np.vstack([self._probe(), self._starts[1][:-1]])
        theta, estimate, ok, spent = self._leading(
            1, starts, lo, tracker.rtol, tracker.max_products, 1
        )
        used, factors = used + spent, factors + 2
        low = lo + 1.0 / theta
        if ok and low < hi and self._certified(low, tracker):
            return low, estimate, used, factors
        while hi - lo > 0.5 * margin * hi:
            mid, factors = 0.5 * (lo + hi), factors + 1
            lo, hi = (mid, hi) if fused.factor_shifted(mid, *self._model) else (lo, mid)
        return hi, (hi - lo) / hi, used, factors

    def sample(self, q: np.ndarray, tracker) -> list:
        """[(λmax, products, fallback, estimate), (λmin, …), factorizations] at q.

        ``stats`` after [`warm_sample`][gimwatch.metrics.tracker.denoc.warm_sample]: λmax, its
        estimate, converged, products (0–3); the same for λmin (4–7); σ, factorizations, M positive
        definite (8–10); a fallback is needed (11), for λmax (12), for λmin (13).
        """
        if not self.sampled:
            return self._start(q, tracker)
        stats = self._stats
        params = np.array([tracker.rtol, tracker.warm_products, tracker.jump])
        warm_sample(
            q, self._geometry, self._model, *self._starts, self._probes, self._state, params,
            *self._work.arrays(), stats,
        )  # fmt: skip
        top, e_top, _, n_top, low, e_low, _, n_low, _, factors, definite, cold = stats[:12].tolist()
        n_top, n_low, factors = int(n_top), int(n_low), int(factors)
        if not cold:
            if self._certified(low, tracker):
                return [(top, n_top, "", e_top), (low, n_low, "", e_low), factors + 1]
            # an eigenvalue below the tracked one (a crossing the warm block missed)
            low, e_low, n_more, more = self._certified_cold_low(tracker)
            previous = self._state[1]
            self._state[:3] = top, low, abs(low - previous) / low
            return [(top, n_top, "", e_top), (low, n_low + n_more, "cold", e_low), factors + more]
        if not definite:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        fb_top = fb_low = ""
        if stats[12]:
            fb_top = "cold"
            top, e_top, ok, used = self._cold(0, 0.0, tracker.rtol, tracker.max_products)
            n_top += used
            if not ok:
                raise ConditioningError(f"λmax did not converge in {tracker.max_products} products")
        if stats[13] or not self._certified(low, tracker):
            fb_low = "cold"
            low, e_low, used, more = self._certified_cold_low(tracker)
            n_low, factors = n_low + used, factors + more
        factors += 1
        previous = self._state[1]
        self._state[:3] = top, low, abs(low - previous) / low
        return [(top, n_top, fb_top, e_top), (low, n_low, fb_low, e_low), factors]

    def _start(self, q: np.ndarray, tracker) -> list:
        """The first sample: both ends from a cold start."""
        model = self._model
        fused.kinematics(q, model[0], self._geometry, *model[1:5])
        top, e_top, ok_top, n_top = self._cold(0, 0.0, tracker.rtol, tracker.max_products)
        low, e_low, n_low, factors = self._certified_cold_low(tracker)
        if not ok_top:
            raise ConditioningError(
                f"the κ tracker did not converge in {tracker.max_products} products "
                "and has no dense fallback"
            )
        self._state[:3] = top, low, 0.0
        self.sampled = True
        return [(top, n_top, "start", e_top), (low, n_low, "start", e_low), factors]
