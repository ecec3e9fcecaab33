"""Matrix-free products with M(q) and M(q)⁻¹, and κ from their extreme eigenvalues.

Pinocchio never has to form M for these:

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

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from scipy.sparse.linalg import ArpackNoConvergence, LinearOperator, eigsh

from gimwatch.denoc.linear import MatrixFreeKappa
from gimwatch.errors import ConditioningError, InputError
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = [
    "gim_inverse_operator",
    "gim_operator",
    "kappa_matrix_free",
]


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
        The [`MatrixFreeKappa`][gimwatch.denoc.MatrixFreeKappa] record, with the eigenvectors for
        the next warm start.
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
