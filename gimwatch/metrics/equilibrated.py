"""κ_S, the condition number of the diagonally equilibrated GIM: dense and from O(n) products.

With D = diag M, S = D^-1/2 M D^-1/2 has a unit diagonal and κ_S = κ₂(S). Then
κ₂(M) ≤ δ · κ_S: δ is the spread of the diagonal, κ_S the coupling between coordinates.

Why it is the number that counts digits: Cholesky (and the LDLᵀ/UDUᵀ recursions) are
invariant to diagonal scaling, so the computed solve of M x = τ has an error bounded in
proportion to κ_S·eps, not κ·eps (van der Sluis 1969; Higham, *Accuracy and Stability of
Numerical Algorithms*, §7.3; LAPACK ``dpoequ``). And κ_S does not change when a coordinate
changes unit (M → T M T with T diagonal: metres to millimetres, radians to degrees), while κ
and δ do.

* [`equilibrated`][gimwatch.metrics.equilibrated.equilibrated] — S from a dense M;
* [`equilibrated_extremes`][gimwatch.metrics.equilibrated.equilibrated_extremes] — (λmin, λmax)
  of S by a symmetric eigen-solve;
* [`ScaledState`][gimwatch.metrics.equilibrated.ScaledState] — S·x and S⁻¹·y from the O(n)
  products of DeNOC's linear-time state and its O(n) diagonal, for
  [`extreme_eigenvalues`][gimwatch.metrics.tracker.extremes.extreme_eigenvalues] (the κ
  tracker's engine);
* [`ScaledProducts`][gimwatch.metrics.equilibrated.ScaledProducts] — the same for any provider of
  the κ tracker (``configure``, ``gim_product``, ``gim_solve``), so that
  [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] tracks κ_S along a trajectory.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

import numpy as np
import numpy.typing as npt

from gimwatch.errors import ConditioningError
from gimwatch.metrics.conditioning import check_gim, eigenvalues

__all__ = [
    "ScaledProducts",
    "ScaledState",
    "equilibrated",
    "equilibrated_dense",
    "equilibrated_extremes",
    "equilibrated_tracker",
]


def _inverse_root(diagonal: npt.ArrayLike) -> np.ndarray:
    """D^-1/2 of a diagonal given as a vector; a non-positive entry makes M singular."""
    d = np.asarray(diagonal, dtype=float)
    if not np.all(d > 0) or not np.all(np.isfinite(d)):
        raise ConditioningError(
            "the GIM's diagonal must be positive and finite to equilibrate it "
            f"(smallest entry {float(np.min(d)) if d.size else float('nan'):.3g})"
        )
    return 1.0 / np.sqrt(d)


def equilibrated(matrix: npt.ArrayLike) -> np.ndarray:
    """S = D^-1/2 M D^-1/2 (unit diagonal) of a checked GIM M.

    Raises:
        ConditioningError: M is not a valid GIM (see `check_gim`).
    """
    M = check_gim(matrix)
    r = _inverse_root(np.diag(M))
    S = M * r[:, None] * r[None, :]
    np.fill_diagonal(S, 1.0)  # exactly: d_i^-1/2 M_ii d_i^-1/2 is 1 up to round-off
    return 0.5 * (S + S.T)


def equilibrated_extremes(matrix: npt.ArrayLike) -> tuple[float, float]:
    """(λmin, λmax) of S = D^-1/2 M D^-1/2, by a symmetric eigen-solve of S (O(n³))."""
    values = eigenvalues(equilibrated(matrix))
    return float(values[0]), float(values[-1])


class ScaledState:
    """S·x and S⁻¹·y of DeNOC's linear-time state at one configuration, O(n) each.

    ``S x = D^-1/2 M (D^-1/2 x)`` and ``S⁻¹ y = D^1/2 M⁻¹ (D^1/2 y)``, with D = diag M from the
    state's O(n) recursion. Exposes ``model`` (for ``nv``), ``matvec`` and ``solve``: what
    [`extreme_eigenvalues`][gimwatch.metrics.tracker.extremes.extreme_eigenvalues] reads.

    Args:
        state: A [`ConfigurationState`][gimwatch.denoc.ConfigurationState] (``diagonal()``,
            ``matvec``, ``solve``).
        diagonal: Diag M in the state's order, when already computed.
    """

    def __init__(self, state, diagonal: np.ndarray | None = None) -> None:
        self.state, self.model = state, state.model
        self.scale = _inverse_root(state.diagonal() if diagonal is None else diagonal)

    def matvec(self, x: npt.ArrayLike) -> np.ndarray:
        """S x."""
        return self.scale * self.state.matvec(self.scale * np.asarray(x, dtype=float))

    def solve(self, y: npt.ArrayLike) -> np.ndarray:
        """S⁻¹ y."""
        return self.state.solve(np.asarray(y, dtype=float) / self.scale) / self.scale


class ScaledProducts:
    """A κ-tracker provider of S = D^-1/2 M D^-1/2 built on a provider of M.

    Args:
        products: A provider of M (``configure(q)``, ``gim_product(x)``, ``gim_solve(y)``):
            DeNOC's lean model or
            [`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts].
        diagonal: ``q ↦ diag M(q)`` in the provider's coordinate order, O(n) (DeNOC's
            ``gim_diagonal``, Pinocchio's composite-inertia diagonal).

    The wrapped provider is not DeNOC's compiled model, so the tracker takes its generic
    path (Lanczos on S⁻¹ with a Ritz block) rather than shift-invert.
    """

    def __init__(self, products, diagonal: Callable[[np.ndarray], np.ndarray]) -> None:
        self.products, self.diagonal = products, diagonal
        self.scale: np.ndarray | None = None

    def configure(self, q: np.ndarray) -> None:
        """Set the configuration of the products and compute D^-1/2 there."""
        self.products.configure(q)
        self.scale = _inverse_root(self.diagonal(q))

    def gim_product(self, x: np.ndarray) -> np.ndarray:
        """S x."""
        return self.scale * self.products.gim_product(self.scale * x)

    def gim_solve(self, y: np.ndarray) -> np.ndarray:
        """S⁻¹ y."""
        return self.products.gim_solve(y / self.scale) / self.scale

    def shifted_inertia(self, shift: float) -> tuple[int, int] | None:
        """(positive, negative) pivots of S − shift·1, or None when M's provider cannot say.

        S − σ·1 = D^-1/2 (M − σ·D) D^-1/2 has the pivot signs of M − σ·D (a congruence), so the
        Sylvester certificate of S exists where M's provider shifts by a diagonal
        (``shifted_inertia(shift, weights)``, as
        [`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts]); DeNOC's
        compiled factor shifts by a multiple of 1 only, and the tracker then leaves κ_S
        uncertified or certifies it on the dense fallback.
        """
        if self.scale is None:
            raise ConditioningError("ScaledProducts.shifted_inertia before configure(q)")
        if not self.shifts_by_diagonal:
            return None
        return self.products.shifted_inertia(shift, weights=self.scale**-2)

    @property
    def shifts_by_diagonal(self) -> bool:
        """Whether M's provider can shift by a diagonal (``shifted_inertia(shift, weights)``)."""
        method = getattr(self.products, "shifted_inertia", None)
        return method is not None and "weights" in inspect.signature(method).parameters


def equilibrated_dense(dense: Callable[[np.ndarray], np.ndarray]):
    """``q ↦ S(q)`` from ``q ↦ M(q)``: the κ tracker's dense fallback, on S."""
    return lambda q: equilibrated(dense(q))


def equilibrated_tracker(robot, dynamics=None, data=None, lean=None):
    """A [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] of κ_S along a trajectory.

    S·x and S⁻¹·y from the cheapest provider of M's O(n) products (DeNOC's compiled model,
    else Pinocchio's RNEA/ABA) and the O(n) diagonal of the same model; the dense fallback
    equilibrates Pinocchio's CRBA (or the backend's) M.

    Args:
        robot: The robot.
        dynamics: A simulation backend (its ``gim`` and lean model are reused).
        data: A Pinocchio Data to reuse.
        lean: DeNOC's compiled model, when the caller has one.
    """
    from gimwatch.metrics.tracker import KappaTracker
    from gimwatch.metrics.tracker.providers import gim_products
    from gimwatch.model.inertia import gim, gim_diagonal

    provider = lean or gim_products(robot, dynamics, data)
    if hasattr(provider, "gim_diagonal"):  # DeNOC's model: its own O(n) diagonal
        diagonal = provider.gim_diagonal
    else:
        own = robot.new_data() if data is None else data
        diagonal = lambda q: gim_diagonal(robot, q, data=own)  # noqa: E731

    def dense(q: np.ndarray) -> np.ndarray:
        return gim(robot, q, data=data) if dynamics is None else dynamics.gim(q)

    products = ScaledProducts(provider, diagonal)
    return KappaTracker(products, robot.nv, dense=equilibrated_dense(dense))
