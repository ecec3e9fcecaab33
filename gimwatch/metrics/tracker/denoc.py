"""The κ tracker on DeNOC's compiled model: one compiled call per warm sample, shift-invert λmin.

[`DenocEnds`][gimwatch.metrics.tracker.denoc.DenocEnds] holds the tracker's own DeNOC buffers (the
LeanModel it was given keeps its configuration) and the state carried from sample to sample: each
end's Ritz block, the last λmin and its last relative change. A warm sample is ONE compiled call,
[`warm_sample`][gimwatch.metrics.tracker.denoc.warm_sample]: kinematics at q (Shah & Saha's DeNOC,
`gimwatch.denoc.fused`), Lanczos on M·x for λmax, the articulated factor of M − σ·1 with σ =
λmin(previous)·(1 − s) (refactored with s × 100 while a pivot is not positive — Sylvester's law of
inertia: then λmin ≤ σ — up to s = 1, the plain M⁻¹), and Lanczos on (M − σ·1)⁻¹ for λmin = σ + 1/θ.
The same call certifies both ends (one factor each: M − λmax(1 + rtol)·1 with only negative
pivots, M − λmin(1 − rtol)·1 with only positive ones). Cold starts (the first sample, and the
detected or uncertified failures of a warm one) run the same compiled pieces from Python, and
recover an end whose certificate fails by Sylvester bisection on the shift.
See [`core`][gimwatch.metrics.tracker.core] for the method and its stopping rule.
"""

from __future__ import annotations

import numpy as np

from gimwatch.denoc import fused
from gimwatch.denoc.lean import LeanModel
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
#: Both ends are certified at every sample by Sylvester's law of inertia: the factor of
#: M − λmin(1 − CERTIFY·rtol)·1 has only positive pivots (no eigenvalue below it) and that of
#: M − λmax(1 + CERTIFY·rtol)·1 only negative ones (no eigenvalue above it). Ritz values lie
#: inside the spectrum, so each reported end is then within CERTIFY·rtol of the true one.
CERTIFY = 1.0
#: Lanczos stops at STOP·rtol (its Kato–Temple estimate), so that the certificate at rtol passes.
STOP = 0.25
#: Whether a warm sample adds a fresh probe to the (λmax, λmin) end's Ritz block (1) or starts
#: that end from the block alone (0). λmax: the certificate catches what the block misses (a failed
#: one brings a probe in, in the cold start), and a warm sample saves a product (5–10 % of its
#: time at n = 100–400). λmin: the probe stays; without it the clustered low modes of a long chain
#: send 3–5× more samples of a random path to a cold start (measured at n = 200 and 400).
WARM_PROBE = (0, 1)


@njit(cache=True)
def _pivot_signs(model):
    """(positive, negative) pivots of the last articulated factor (NaN pivots count as neither)."""
    index, floating, scal, root = model[0], model[1], model[6], model[7]
    positive = negative = 0
    for i in range(index.shape[0]):
        kind = index[i, 1]
        if i == 0:  # the base: six pivots when it floats, none when it is the world
            width = 6 if floating else 0
        else:  # a free joint's body six, a ball's three (their UDUᵀ blocks), else one
            width = 6 if kind == 4 else (3 if kind == 5 else 0)
        if width:
            for k in range(width):
                positive += root[i, 6, k] > 0.0
                negative += root[i, 6, k] < 0.0
        elif i > 0:
            positive += scal[i, 0] > 0.0
            negative += scal[i, 0] < 0.0
    return positive, negative


@njit(cache=True)
def nothing_above(shift, size, model):
    """Whether no eigenvalue of M lies at or above ``shift``: every pivot of M − shift·1 < 0."""
    index, floating, rot, vec, block, six, scal, root = model
    fused.factor_shifted(shift, index, floating, rot, vec, block, six, scal, root)
    return _pivot_signs(model)[1] == size


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
def warm_sample(  # noqa: PLR0913  # numba kernel: flat arrays
    q, geometry, model, starts_max, starts_min, probes, state, params, V, AV, H, vectors, stats
):
    """One warm sample in one call, both ends certified (see `DenocEnds.sample` for ``stats``).

    Args:
        q: Configuration (Pinocchio's order).
        geometry: The packed tree
            ([`compiled_model_arguments`][gimwatch.denoc.LeanModel.compiled_model_arguments]).
        model: (index, floating, rot, vec, block, six, scal, root): the tracker's buffers.
        starts_max: The λmax end's Ritz block (rows, leading last) and a probe row (read only
            with ``WARM_PROBE``); the block is overwritten with the new Ritz vectors.
        starts_min: The same for the λmin end.
        probes: Seeded probe vectors, used in turn.
        state: [λmax, λmin, last relative change of λmin, probes used], updated in place when
            both ends succeed.
        params: [Lanczos tolerance, warm product budget, jump, certificate margin (relative),
            1 to add the probe rows to the blocks, 0 not to].
        V: Krylov workspace ([`Workspace`][gimwatch.metrics.tracker.krylov.Workspace]), with AV,
            H and vectors.
        AV: See V.
        H: See V.
        vectors: See V.
        stats: Receives the results
            ([`DenocEnds.sample`][gimwatch.metrics.tracker.denoc.DenocEnds.sample]).
    """
    rtol, budget, jump, margin = params[0], int(params[1]), params[2], params[3]
    probe_max, probe_min = int(params[4]), int(params[5])  # 1: a probe joins that end's block
    size = starts_max.shape[1]
    used = int(state[3])
    starts_max[-1] = probes[used % probes.shape[0]]
    starts_min[-1] = probes[(used + 1) % probes.shape[0]]
    state[3] = used + 2
    index, floating, rot, vec, block = model[0], model[1], model[2], model[3], model[4]
    fused.kinematics(q, index, geometry, floating, rot, vec, block)
    keep = starts_max.shape[0] - 1
    top, e_top, ok_top, n_top = leading(
        0, starts_max, keep + probe_max, 0.0, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_max, model,
    )  # fmt: skip
    stats[:] = 0.0
    cold_top = not ok_top or abs(top - state[0]) > jump * state[0]
    factors = 0
    if not cold_top:
        factors += 1
        stats[15] = 1.0 if nothing_above(top * (1.0 + margin), size, model) else 0.0
    s = max(_MARGIN * state[2], _SHIFT_MIN)
    sigma, more, definite = _factor_with_margin(state[1], s, model)
    factors += more
    stats[0], stats[1], stats[2], stats[3] = top, e_top, ok_top, n_top
    stats[8], stats[10] = sigma, definite
    stats[12] = cold_top
    stats[9] = factors
    if not definite:
        stats[11] = 1.0
        return
    keep = starts_min.shape[0] - 1
    theta, e_low, ok_low, n_low = leading(
        1, starts_min, keep + probe_min, sigma, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_min, model,
    )  # fmt: skip
    low = sigma + 1.0 / theta
    stats[4], stats[5], stats[6], stats[7] = low, e_low, ok_low, n_low
    cold_low = not ok_low or abs(low - state[1]) > jump * state[1]
    if not cold_low:
        stats[9] = factors + 1
        shift = low * (1.0 - margin)
        positive = fused.factor_shifted(
            shift, index, floating, rot, vec, block, model[5], model[6], model[7]
        )
        stats[14] = 1.0 if positive else 0.0
    stats[13] = cold_low
    certified = stats[14] == 1.0 and stats[15] == 1.0
    stats[11] = 0.0 if certified and not (cold_top or cold_low) else 1.0
    if stats[11] == 0.0:
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
        self._stats = np.zeros(16)
        self._probes = np.random.default_rng(seed + 1).standard_normal((_PROBES, n))
        self._state = np.zeros(4)  # λmax, λmin, relative change of λmin, probes used
        self._arguments: tuple | None = None  # warm_sample's, after q
        self._settings: tuple = ()
        self.sampled = False

    @classmethod
    def of(cls, products, n: int, keep: tuple[int, int], seed: int = 0) -> DenocEnds | None:
        """The compiled ends for DeNOC's LeanModel; None for any other provider."""
        if not isinstance(products, LeanModel):
            return None
        return cls(products, n, keep, seed)

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
            which, starts, starts.shape[0], sigma, rtol * STOP, budget, keep, _CHECK_EVERY,
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

    def _nothing_above(self, shift: float) -> bool:
        return bool(nothing_above(shift, self.n, self._model))

    def _certified_cold_low(self, tracker) -> tuple[float, float, int, int]:
        """λmin from a cold start, certified; (λmin, its bound, products, factorizations).

        The bound b brackets λmin in [λ(1 − b), λ]. Raises ConditioningError when it did not
        converge (the tracker then uses its dense fallback when it has one).
        """
        low, _, ok, used, factors = self._cold_low(tracker)
        if not ok:
            raise ConditioningError(f"λmin did not converge in {tracker.max_products} products")
        factors += 1
        if self._certified(low, tracker):
            return low, CERTIFY * tracker.rtol, used, factors
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
        theta, _, ok, spent = self._leading(1, starts, lo, tracker.rtol, tracker.max_products, 1)
        used, factors = used + spent, factors + 2
        low = lo + 1.0 / theta
        if ok and low < hi and self._certified(low, tracker):
            return low, margin, used, factors
        while hi - lo > margin * hi:
            mid, factors = 0.5 * (lo + hi), factors + 1
            lo, hi = (mid, hi) if fused.factor_shifted(mid, *self._model) else (lo, mid)
        return hi, 1.0 - lo / hi, used, factors

    def _certified_cold_top(self, lower: float, tracker) -> tuple[float, float, int, int]:
        """λmax from a cold start, certified; (λmax, its bound b, products, factorizations).

        λmax lies in [λ, λ(1 + b)]. ``lower`` is a known lower bound (a Ritz value). Lanczos
        from a probe and the Ritz block; when the factor of M − λ(1 + CERTIFY·rtol)·1 still
        has a pivot that is not negative (a mode above it the Krylov space has not resolved:
        the two largest eigenvalues cross), λmax is bracketed by Sylvester bisection on the
        shift to the tolerance, and the block is given its eigenvector by inverse iteration
        just above it.
        """
        margin = CERTIFY * tracker.rtol
        theta, _, ok, used = self._cold(0, 0.0, tracker.rtol, tracker.max_products)
        factors = 1
        lower = max(lower, theta)
        if not lower > 0.0:
            raise ConditioningError(f"M(q) must be positive definite, got λmax ≤ {lower:.6g}")
        if ok and self._nothing_above(theta * (1.0 + margin)):
            return theta, margin, used, factors
        step = margin
        while not self._nothing_above(lower * (1.0 + step)):
            step, factors = 4.0 * step, factors + 1
            if step > 1e8:  # no shift clears the spectrum: a pivot is zero or not a number
                raise ConditioningError("λmax could not be bracketed: M(q) is singular")
        lo, hi = lower, lower * (1.0 + step)
        while hi - lo > margin * lo:
            mid, factors = 0.5 * (lo + hi), factors + 1
            lo, hi = (lo, mid) if self._nothing_above(mid) else (mid, hi)
        self._top_vector(hi)
        return lo, hi / lo - 1.0, used + 2, factors + 1

    def _top_vector(self, shift: float) -> None:
        """Two steps of inverse iteration on M − shift·1 (shift just above λmax) into the block."""
        fused.factor_shifted(shift, *self._model)
        vector, out = self._probe().copy(), np.empty(self.n)
        for _ in range(2):
            fused.gim_solve(vector, *self._model, out)
            vector = out / np.linalg.norm(out)
        self._starts[0][-2] = vector

    def sample(self, q: np.ndarray, tracker) -> list:
        """[(λmax, products, fallback, bound), (λmin, …), factorizations] at q.

        ``stats`` after [`warm_sample`][gimwatch.metrics.tracker.denoc.warm_sample]: λmax, its
        estimate, converged, products (0–3); the same for λmin (4–7); σ, factorizations, M positive
        definite (8–10); a fallback is needed (11), for λmax (12), for λmin (13); λmin certified
        (14), λmax certified (15). A bound b brackets λmax in [λ, λ(1 + b)], λmin in
        [λ(1 − b), λ].
        """
        if not self.sampled:
            return self._start(q, tracker)
        stats, margin = self._stats, CERTIFY * tracker.rtol
        settings = (tracker.rtol * STOP, tracker.warm_products, tracker.jump, margin, *WARM_PROBE)
        if self._arguments is None or settings != self._settings:
            # built once: the Python side of a warm sample is a good part of its cost at n ≤ 100
            self._settings = settings
            self._arguments = (
                self._geometry, self._model, *self._starts, self._probes, self._state,
                np.array(settings), *self._work.arrays(), stats,
            )  # fmt: skip
        warm_sample(q, *self._arguments)
        top, _, _, n_top, low, _, _, n_low, _, factors, definite, cold = stats[:12].tolist()
        n_top, n_low, factors = int(n_top), int(n_low), int(factors)
        if not cold:
            return [(top, n_top, "", margin), (low, n_low, "", margin), factors]
        if not definite:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        fb_top = fb_low = ""
        b_top = b_low = margin
        if stats[12] or not stats[15]:
            fb_top = "cold"
            top, b_top, used, more = self._certified_cold_top(top, tracker)
            n_top, factors = n_top + used, factors + more
        if stats[13] or not stats[14]:
            fb_low = "cold"
            low, b_low, used, more = self._certified_cold_low(tracker)
            n_low, factors = n_low + used, factors + more
        previous = self._state[1]
        self._state[:3] = top, low, abs(low - previous) / low
        return [(top, n_top, fb_top, b_top), (low, n_low, fb_low, b_low), factors]

    def _start(self, q: np.ndarray, tracker) -> list:
        """The first sample: both ends from a cold start, certified."""
        model = self._model
        fused.kinematics(q, model[0], self._geometry, *model[1:5])
        top, b_top, n_top, f_top = self._certified_cold_top(0.0, tracker)
        low, b_low, n_low, factors = self._certified_cold_low(tracker)
        self._state[:3] = top, low, 0.0
        self.sampled = True
        return [(top, n_top, "start", b_top), (low, n_low, "start", b_low), factors + f_top]
