"""κ₂ at one configuration from O(n) operators only: one cold, certified sample of the κ tracker.

[`extreme_eigenvalues`][gimwatch.metrics.tracker.extremes.extreme_eigenvalues] serves the O(n)
path of ``analyze`` (κ and κ_S of chains and trees DeNOC reads, M never formed) and the registry's
``extremes`` on that path. It is not a Krylov method of its own: it runs the first sample of a
[`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] (the tracker's engine,
[`gimwatch.metrics.tracker.krylov`][gimwatch.metrics.tracker.krylov]).

* On a DeNOC state (``DenocModel.state(q)``), the tracker runs on the state's compiled model:
  λmax by Lanczos on M·x, λmin by shift-invert Lanczos on (M − σ·1)⁻¹ with σ refined towards it,
  and both ends certified by Sylvester's law of inertia (pivot signs of M − shift·1). The
  smallest eigenvalues of a long chain cluster within relative gaps ~1/n²; shift-invert
  separates them, and λmin keeps its relative accuracy where a dense eigen-solver (absolute error
  ~eps·λmax) no longer resolves it.
* On any other pair of operators (``matvec``, ``solve``: S = D^-1/2 M D^-1/2 of
  `gimwatch.metrics.equilibrated.ScaledState`), Lanczos on each with a block of
  Ritz vectors; without a way to count eigenvalues past a shift the result is not certified
  (``certified`` False, ``error_estimate`` inf).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gimwatch.denoc import ConfigurationState, LeanState
from gimwatch.metrics.tracker.core import KappaTracker, TrackedKappa, TrackerSettings

__all__ = ["extreme_eigenvalues"]


class _Operators:
    """A tracker provider from a state's two O(n) operators (the state holds its q)."""

    def __init__(
        self, matvec: Callable[[np.ndarray], np.ndarray], solve: Callable[[np.ndarray], np.ndarray]
    ) -> None:
        self.gim_product, self.gim_solve = matvec, solve

    def configure(self, q: np.ndarray) -> None:
        """Nothing to set: the state is at its configuration already."""


def extreme_eigenvalues(
    state, *, seed: int = 0, rtol: float = 1e-10, max_products: int | None = None
) -> TrackedKappa:
    """κ₂ = λmax / λmin of the state's M (or of its operator pair) with O(n) products only.

    Args:
        state: A DeNOC state (``DenocModel.state(q)``: a
            [`ConfigurationState`][gimwatch.denoc.ConfigurationState] or
            [`LeanState`][gimwatch.denoc.LeanState]), or any object with ``model.nv``,
            ``matvec(x)`` and ``solve(y)`` of a symmetric positive definite operator.
        seed: Seed of the random probe vectors.
        rtol: Relative tolerance on each extreme eigenvalue (certified on a DeNOC state: the
            true κ lies in [κ, κ·(1 + error_estimate)]).
        max_products: Products per end at most (default 400 + 4 n).

    Returns:
        The tracker's [`TrackedKappa`][gimwatch.metrics.tracker.TrackedKappa] record (products,
        factorizations, whether certified).

    Raises:
        ConditioningError: M is not positive definite, or Lanczos did not converge.
    """
    nv = state.model.nv
    settings = TrackerSettings(rtol=rtol, max_products=max_products, seed=seed)
    if isinstance(state, ConfigurationState | LeanState):
        lean, q = state.compiled()
        return KappaTracker(lean, nv, settings).sample(q)
    operators = _Operators(state.matvec, state.solve)
    return KappaTracker(operators, nv, settings).sample(np.zeros(0))
