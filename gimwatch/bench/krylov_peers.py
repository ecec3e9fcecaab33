"""The Krylov engines the κ tracker replaced, kept as bench peers: ARPACK and plain Lanczos.

Not metrics: every matrix-free κ of gimwatch runs on the κ tracker's Krylov engine
([`gimwatch.metrics.tracker.krylov`][gimwatch.metrics.tracker.krylov]). This module keeps the
engines used before it, so that the bench can time the tracker against them and the tests can
check them against LAPACK: [`kappa_matrix_free`][gimwatch.bench.krylov_peers.kappa_matrix_free]
(ARPACK on Pinocchio's RNEA/ABA, the watch's former ``kappa_lanczos``) and
[`plain_lanczos_kappa`][gimwatch.bench.krylov_peers.plain_lanczos_kappa] (Lanczos without
restarts on DeNOC's O(n) state, the O(n) path's former κ). Pinocchio never has to form M for
these:

* ``M(q) x = RNEA(q, v = 0, a = x)`` with gravity off (the inverse-dynamics torque of an
  acceleration ``x`` from rest), O(n) per product;
* ``M(q)⁻¹ y = ABA(q, v = 0, tau = y)`` with gravity off (the forward-dynamics
  acceleration of a torque ``y`` from rest), O(n) per product.

Lanczos (ARPACK through `scipy.sparse.linalg.eigsh`) on the first operator gives
λmax, on the second 1/λmin, so κ₂ = λmax / λmin (Shah & Saha 2013, Eq. 6) costs a few dozen
O(n) recursions instead of an O(n³) eigen-solve. The start vector is random and seeded: a
vector of ones is nearly orthogonal to the smallest eigenvectors of straight chains, and
Lanczos then converges to the wrong end of the spectrum. Passing the previous sample's
eigenvectors as ``start`` warm-starts a sweep.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt
import pinocchio as pin
import scipy.linalg
from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

from gimwatch.errors import ConditioningError, InputError
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = [
    "MatrixFreeKappa",
    "gim_inverse_operator",
    "gim_operator",
    "kappa_matrix_free",
    "plain_lanczos_kappa",
]


@dataclass(frozen=True)
class MatrixFreeKappa:
    """κ₂ of M(q) from a peer engine on x ↦ M x and x ↦ M⁻¹ x (M never formed).

    Attributes:
        kappa: λmax / λmin.
        lambda_max: Largest eigenvalue of M.
        lambda_min: Smallest eigenvalue of M (1 / the largest of M⁻¹).
        products: O(n) products applied (M·x and M⁻¹·x together).
        last_relative_change: Plain Lanczos: relative change of the Ritz values over the last
            10 steps (below ``rtol`` when converged); NaN from ARPACK (it checks residuals).
        vector_max: ARPACK: eigenvector of λmax, to warm-start a nearby sample (else None).
        vector_min: ARPACK: eigenvector of λmin (else None).
    """

    kappa: float
    lambda_max: float
    lambda_min: float
    products: int
    last_relative_change: float = float("nan")
    vector_max: np.ndarray | None = field(default=None, repr=False)
    vector_min: np.ndarray | None = field(default=None, repr=False)


def _zero_gravity_model(robot: Robot) -> pin.Model:
    model = pin.Model(robot.model)
    model.gravity = pin.Motion.Zero()
    return model


class _Counter:
    def __init__(self) -> None:
        self.count = 0


def _operator(robot: Robot, q: npt.ArrayLike, data: pin.Data | None, kind: str) -> LinearOperator:
    q = as_configuration(robot, q)
    data = robot.new_data() if data is None else data
    model = _zero_gravity_model(robot)
    zero = np.zeros(robot.nv)
    counter = _Counter()
    algorithm = pin.rnea if kind == "M" else pin.aba

    def matvec(x: np.ndarray) -> np.ndarray:
        counter.count += 1
        return np.array(algorithm(model, data, q, zero, np.ravel(x)))

    operator = LinearOperator((robot.nv, robot.nv), matvec=matvec, rmatvec=matvec, dtype=float)
    operator.counter = counter  # products so far, for cost accounting
    return operator


def gim_operator(robot: Robot, q: npt.ArrayLike, *, data: pin.Data | None = None) -> LinearOperator:
    """M(q) as a LinearOperator: ``x ↦ RNEA(q, 0, x)`` with gravity off, O(n) per product.

    Args:
        robot: The robot.
        q: Configuration, length nq.
        data: A Pinocchio Data to reuse (one is made when omitted).
    """
    return _operator(robot, q, data, "M")


def gim_inverse_operator(
    robot: Robot, q: npt.ArrayLike, *, data: pin.Data | None = None
) -> LinearOperator:
    """M(q)⁻¹ as a LinearOperator: ``y ↦ ABA(q, 0, y)`` with gravity off, O(n) per product.

    Args:
        robot: The robot.
        q: Configuration, length nq.
        data: A Pinocchio Data to reuse (one is made when omitted).
    """
    return _operator(robot, q, data, "Minv")


def _largest(operator: LinearOperator, v0: np.ndarray, tol: float) -> tuple[float, np.ndarray]:
    n = operator.shape[0]
    if n == 1:
        value = float(operator.matvec(np.ones(1))[0])
        return value, np.ones(1)
    if n <= 2:  # ARPACK needs k < n; a 2x2 is solved densely from two products
        dense = np.column_stack([operator.matvec(e) for e in np.eye(n)])
        values, vectors = np.linalg.eigh((dense + dense.T) / 2)
        return float(values[-1]), vectors[:, -1]
    try:
        values, vectors = eigsh(operator, k=1, which="LA", v0=v0, tol=tol)
    except ArpackNoConvergence as exc:
        raise ConditioningError(f"Lanczos did not converge ({exc})") from exc
    return float(values[0]), vectors[:, 0]


def kappa_matrix_free(
    robot: Robot,
    q: npt.ArrayLike,
    *,
    data: pin.Data | None = None,
    seed: int | None = 0,
    tol: float = 1e-10,
    start: tuple[np.ndarray, np.ndarray] | None = None,
) -> MatrixFreeKappa:
    """κ₂(M(q)) = λmax / λmin without forming M (Shah & Saha 2013, Eq. 6).

    λmax is the largest eigenvalue of the RNEA operator, λmin the reciprocal of the largest
    eigenvalue of the ABA operator; both come from implicitly restarted Lanczos (ARPACK).

    Args:
        robot: The robot.
        q: Configuration, length nq.
        data: A Pinocchio Data to reuse (one is made when omitted).
        seed: Seed of the random start vector (used when ``start`` is None).
        tol: ARPACK's relative accuracy of each eigenvalue (0 = machine precision);
            low accuracies (1e-2 … 1e-4) are cheap and enough for a watch.
        start: ``(vector_max, vector_min)`` of a previous, nearby sample to warm-start from.

    Returns:
        The [`MatrixFreeKappa`][gimwatch.bench.krylov_peers.MatrixFreeKappa] record, with the
        eigenvectors for the next warm start.
    """
    q = as_configuration(robot, q)
    if not (np.isfinite(tol) and tol >= 0):
        raise InputError("tol", "finite and >= 0", tol)
    data = robot.new_data() if data is None else data
    if start is None:
        rng = np.random.default_rng(seed)
        v_max, v_min = rng.standard_normal(robot.nv), rng.standard_normal(robot.nv)
    else:
        v_max, v_min = (np.asarray(v, dtype=float) for v in start)
        if v_max.shape != (robot.nv,) or v_min.shape != (robot.nv,):
            raise InputError("start", f"two vectors of length {robot.nv}", (v_max.shape,))
    forward = gim_operator(robot, q, data=data)
    inverse = gim_inverse_operator(robot, q, data=data)
    lambda_max, vector_max = _largest(forward, v_max, tol)
    inverse_max, vector_min = _largest(inverse, v_min, tol)
    if not (lambda_max > 0 and inverse_max > 0):
        raise ConditioningError(
            f"M(q) must be positive definite, got λmax = {lambda_max:.6g}, "
            f"1/λmin = {inverse_max:.6g}"
        )
    lambda_min = 1.0 / inverse_max
    return MatrixFreeKappa(
        kappa=lambda_max / lambda_min,
        lambda_max=lambda_max,
        lambda_min=lambda_min,
        products=forward.counter.count + inverse.counter.count,
        vector_max=vector_max,
        vector_min=vector_min,
    )


def _largest_ritz_value(apply, start: np.ndarray, *, rtol: float, max_steps: int):
    """Largest eigenvalue of a symmetric operator by plain Lanczos, O(n) memory.

    No restarts: the smallest eigenvalues of a long chain's M are clustered (relative gaps
    ~1/n²), where restarted ARPACK (``eigsh``) needs 10^4–10^5 products at n = 10^4 while
    the largest Ritz value itself settles in a few hundred steps. No reorthogonalisation
    either: losing orthogonality only adds spurious copies of converged Ritz values, never
    moves the extreme one, and keeping the basis would cost O(n·steps) memory. Stops when
    the largest Ritz value changes by less than ``rtol`` (relative) over 10 steps.

    Returns:
        (Ritz value, steps taken, its relative change over the last 10 steps).
    """
    v = start / np.linalg.norm(start)
    v_previous = np.zeros_like(v)
    alphas: list[float] = []
    betas: list[float] = []
    beta = 0.0
    previous = np.nan
    steps = min(max_steps, start.size)
    for k in range(steps):
        w = apply(v) - beta * v_previous
        alpha = float(w @ v)
        w -= alpha * v
        alphas.append(alpha)
        beta = float(np.linalg.norm(w))
        exhausted = beta <= 1e-14 * max(abs(a) for a in alphas) or k == steps - 1
        if k % 10 == 9 or exhausted:
            theta = scipy.linalg.eigh_tridiagonal(
                np.array(alphas),
                np.array(betas),
                eigvals_only=True,
                select="i",
                select_range=(k, k),
            )[0]
            change = abs(theta - previous) / abs(theta)
            if exhausted or change <= rtol:
                return float(theta), k + 1, float(change) if k >= 10 else 0.0
            previous = theta
        betas.append(beta)
        v_previous, v = v, w / beta
    raise AssertionError("unreachable")  # the loop returns at its last step


def plain_lanczos_kappa(
    state, *, seed: int = 0, rtol: float = 1e-10, max_steps: int = 3000
) -> MatrixFreeKappa:
    """κ₂ of a DeNOC state by plain Lanczos on ``matvec`` and ``solve``.

    The O(n) path's κ before the tracker's engine served it: one seeded random start for both
    ends, each stopped when its largest Ritz value changes by less than ``rtol`` over 10 steps
    (no certificate; a lower bound of κ that converges to it).
    """
    start = np.random.default_rng(seed).standard_normal(state.model.nv)
    top, steps_max, change_max = _largest_ritz_value(
        state.matvec, start, rtol=rtol, max_steps=max_steps
    )
    inverse, steps_min, change_min = _largest_ritz_value(
        state.solve, start, rtol=rtol, max_steps=max_steps
    )
    if not (top > 0 and inverse > 0):
        raise ConditioningError("the GIM must be positive definite (Lanczos found λ <= 0)")
    return MatrixFreeKappa(
        kappa=float(top * inverse),
        lambda_max=float(top),
        lambda_min=float(1.0 / inverse),
        products=steps_max + steps_min,
        last_relative_change=max(change_max, change_min),
    )
