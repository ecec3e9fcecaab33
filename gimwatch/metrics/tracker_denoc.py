"""The κ tracker on DeNOC's compiled model: one compiled call per warm sample, shift-invert λmin.

:class:`DenocEnds` holds the tracker's own DeNOC buffers (the LeanModel it was given keeps
its configuration) and the state carried from sample to sample: each end's Ritz block, the
last λmin and its last relative change. A warm sample is ONE compiled call,
:func:`warm_sample`: kinematics at q (Shah & Saha's DeNOC, :mod:`gimwatch.denoc.fused`),
Lanczos on M·x for λmax, the articulated factor of M − σ·1 with σ = λmin(previous)·(1 − s)
(refactored with s × 100 while a pivot is not positive — Sylvester's law of inertia: then
λmin ≤ σ — up to s = 1, the plain M⁻¹), and Lanczos on (M − σ·1)⁻¹ for λmin = σ + 1/θ.
Cold starts (the first sample, and the detected failures of a warm one) run the same
compiled pieces from Python: λmin first to 1e-7 on M⁻¹, then shift-invert to the tolerance.
See :mod:`gimwatch.metrics.tracker` for the method and its stopping rule.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from gimwatch.denoc import fused
from gimwatch.errors import ConditioningError
from gimwatch.metrics.tracker_krylov import Workspace, leading

__all__ = ["DenocEnds", "warm_sample"]

_CHECK_EVERY = 2  # products between Rayleigh–Ritz checks: shift-invert converges in a few
_SHIFT_MIN = 1e-10  # smallest relative shift margin s
_SHIFT_COLD = 1e-5  # s after a cold estimate of λmin to 1e-7
_LOOSE = 1e-7  # tolerance of the cold start's first, unshifted estimate of λmin
_PROBES = 16  # seeded probe vectors, used in turn


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
    q, geometry, model, starts_max, starts_min, low, s, rtol, budget, V, AV, H, vectors, stats
):
    """One warm sample in one call; results in ``stats`` (see :meth:`DenocEnds.sample`).

    ``starts_max`` / ``starts_min``: each end's Ritz block (rows, leading last) followed by
    one probe row; the blocks are overwritten with the new Ritz vectors.
    """
    index, floating, rot, vec, block = model[0], model[1], model[2], model[3], model[4]
    fused.kinematics(q, index, geometry, floating, rot, vec, block)
    keep = starts_max.shape[0] - 1
    top, e_top, ok_top, n_top = leading(
        0, starts_max, keep + 1, 0.0, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_max, model,
    )  # fmt: skip
    sigma, factors, definite = _factor_with_margin(low, s, model)
    stats[0], stats[1], stats[2], stats[3] = top, e_top, ok_top, n_top
    stats[8], stats[9], stats[10] = sigma, factors, definite
    if not definite:
        return
    keep = starts_min.shape[0] - 1
    theta, e_low, ok_low, n_low = leading(
        1, starts_min, keep + 1, sigma, rtol, budget, keep, _CHECK_EVERY, V, AV, H, vectors,
        starts_min, model,
    )  # fmt: skip
    stats[4], stats[5], stats[6], stats[7] = sigma + 1.0 / theta, e_low, ok_low, n_low


class DenocEnds:
    """Both ends of the κ tracker on a :class:`~gimwatch.denoc.lean.LeanModel`.

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
        self._stats = np.zeros(11)
        self._probes = np.random.default_rng(seed + 1).standard_normal((_PROBES, n))
        self._next_probe = 0
        self._top = self._low = np.nan
        self._change = 0.0
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
        self._top, self._low, self._change, self.sampled = top, low, 0.0, True

    def _probe(self) -> np.ndarray:
        probe = self._probes[self._next_probe % _PROBES]
        self._next_probe += 1
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
        """λmin from a cold start: to 1e-7 on M⁻¹, then shift-invert to the tolerance."""
        sigma, factors, definite = _factor_with_margin(1.0, 1.0, self._model)
        if not definite:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        theta, _, _, used = self._cold(1, 0.0, _LOOSE, tracker.max_products)
        sigma, more, _ = _factor_with_margin(1.0 / theta, _SHIFT_COLD, self._model)
        theta, estimate, ok, extra = self._leading(
            1, self._starts[1], sigma, tracker.rtol, tracker.max_products, 1
        )
        return sigma + 1.0 / theta, estimate, ok, used + extra, factors + more

    def sample(self, q: np.ndarray, tracker) -> list:
        """[(λmax, products, fallback, estimate), (λmin, …), factorizations] at q."""
        stats, model = self._stats, self._model
        if not self.sampled:
            fused.kinematics(q, model[0], self._geometry, *model[1:5])
            top, e_top, ok_top, n_top = self._cold(0, 0.0, tracker.rtol, tracker.max_products)
            low, e_low, ok_low, n_low, factors = self._cold_low(tracker)
            if not (ok_top and ok_low):
                raise ConditioningError(
                    f"the κ tracker did not converge in {tracker.max_products} products "
                    "and has no dense fallback"
                )
            self._top, self._low, self.sampled = top, low, True
            return [(top, n_top, "start", e_top), (low, n_low, "start", e_low), factors]
        for starts in self._starts:
            starts[-1] = self._probe()
        s = max(3.0 * self._change, _SHIFT_MIN)
        warm_sample(
            q, self._geometry, model, *self._starts, self._low, s, tracker.rtol,
            tracker.warm_products, *self._work.arrays(), stats,
        )  # fmt: skip
        if not stats[10]:
            raise ConditioningError("M(q) is singular: an articulated-body pivot is not positive")
        top, e_top, n_top = stats[0], stats[1], int(stats[3])
        low, e_low, n_low, factors = stats[4], stats[5], int(stats[7]), int(stats[9])
        fb_top = fb_low = ""
        if not stats[2] or abs(top - self._top) > tracker.jump * self._top:
            fb_top = "cold"
            top, e_top, ok, used = self._cold(0, 0.0, tracker.rtol, tracker.max_products)
            n_top += used
            if not ok:
                raise ConditioningError(f"λmax did not converge in {tracker.max_products} products")
        if not stats[6] or abs(low - self._low) > tracker.jump * self._low:
            fb_low = "cold"
            low, e_low, ok, used, more = self._cold_low(tracker)
            n_low, factors = n_low + used, factors + more
            if not ok:
                raise ConditioningError(f"λmin did not converge in {tracker.max_products} products")
        self._change = abs(low - self._low) / low
        self._top, self._low = top, low
        return [(top, n_top, fb_top, e_top), (low, n_low, fb_low, e_low), factors]
