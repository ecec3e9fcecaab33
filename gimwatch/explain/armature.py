"""The smallest joint armature that brings κ under a target at given configurations, and its price.

Adding armature a (rotor inertia reflected through the gears, one value per coordinate) turns
M into ``M + diag(a)``. For a target κ_T > 1 and configurations q_1..q_K:

* **uniform** (the same a on every coordinate): ``κ(M + aI) = (λmax + a)/(λmin + a)``, so
  ``κ ≤ κ_T ⇔ a ≥ (λmax − κ_T λmin)/(κ_T − 1)``; the smallest a is the maximum of that over
  the configurations (0 if κ ≤ κ_T already). Closed form, minimal exactly; it is returned
  raised by ``margin`` (relative, 1e-9 by default) so that float64's eigenvalues of the
  applied matrices meet the target.
* **per joint, least total** (minimise Σ a_i): ``g_k(a) = λmax(M_k + diag a) − κ_T
  λmin(M_k + diag a)`` is convex in a (λmax is convex, λmin concave), so the feasible set is
  convex and the problem is a convex program with a linear objective. It is solved by
  Kelley's cutting planes: each iterate's violated ``g_k`` adds the cut ``g_k(a_j) + ∇g_k ·
  (a − a_j) ≤ 0`` with ``∂g_k/∂a_i = u_i² − κ_T w_i²`` (u, w: unit eigenvectors of λmax,
  λmin), an outer approximation, so each LP's optimum is a **lower bound** on the least total.
  The iterate made feasible by the closed-form uniform lift above is an **upper bound**. The
  loop stops when they agree to ``rtol``: the answer is feasible and within ``rtol`` of the
  least total (a certificate, not a heuristic).

The price is stated: the relative change of q̈ under gravity alone (τ = 0),
``‖(M + A)⁻¹ g − M⁻¹ g‖ / ‖M⁻¹ g‖`` at each configuration, and κ is recomputed with the
armature set in Pinocchio's ``model.armature`` (the CRBA adds it to M's diagonal).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin
from scipy.optimize import linprog

from gimwatch.errors import ConditioningError, InputError
from gimwatch.joint_kinds import JointKind, joint_kind
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.dense_analysis import check_robot_gim
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = [
    "MAX_MATRIX_BYTES",
    "ArmaturePlan",
    "least_total",
    "max_configurations",
    "minimal_armature",
]

MAX_CUTS = 500
#: The memory the K matrices M(q_k) kept by the cutting planes may take (float64): 1 GiB.
MAX_MATRIX_BYTES = 1 << 30


def max_configurations(nv: int) -> int:
    """The most configurations whose K nv x nv float64 matrices fit in `MAX_MATRIX_BYTES`."""
    return max(1, MAX_MATRIX_BYTES // (8 * max(nv, 1) ** 2))


def _check_inputs(robot: Robot, qs: np.ndarray, target: float, margin: float) -> None:
    if not np.isfinite(target) or target <= 1.0:
        raise InputError("target", "a number > 1 (κ ≥ 1 always)", target)
    if not (np.isfinite(margin) and margin >= 0):
        raise InputError(
            "margin", "a finite number >= 0 (a negative one misses the target)", margin
        )
    if robot.floating:
        raise InputError("the robot", "fixed-base (no armature on a free-flyer)", robot.name)
    for joint, name in zip(robot.model.joints[1:], robot.model.names[1:], strict=True):
        if joint_kind(joint) is JointKind.FREE_FLYER:  # a file's own free joint, as gimwatch's
            raise InputError(
                f"joint '{name}' of {robot.name}",
                "a joint that can take armature, not a free joint (its 6 DoF move a "
                "floating body, no rotor)",
                "free",
            )
    if qs.shape[0] == 0:
        raise InputError("configurations", "at least one configuration", "none")
    fits = max_configurations(robot.nv)
    if qs.shape[0] > fits:
        raise InputError(
            "configurations",
            f"at most {fits} for nv = {robot.nv} (K nv x nv float64 matrices within the "
            f"{MAX_MATRIX_BYTES >> 20} MiB budget)",
            qs.shape[0],
        )


@dataclass(frozen=True)
class ArmaturePlan:
    """Armature to add, and what it does.

    Attributes:
        robot: Robot name.
        target: κ_T.
        per_joint: Whether each coordinate got its own value (else one uniform value).
        dof_names: Names of the velocity coordinates.
        armature: Armature to add per coordinate (kg·m² revolute, kg prismatic).
        lower_bound: A lower bound on the least total armature (= the total for uniform).
        kappa_before: κ at each configuration without the added armature.
        kappa_after: κ at each configuration recomputed with it (Pinocchio model.armature).
        qdd_change: Relative change of q̈ under gravity at each configuration.
        iterations: Cutting-plane LPs solved (0 for uniform).
    """

    robot: str
    target: float
    per_joint: bool
    dof_names: tuple[str, ...]
    armature: tuple[float, ...]
    lower_bound: float
    kappa_before: tuple[float, ...]
    kappa_after: tuple[float, ...]
    qdd_change: tuple[float, ...]
    iterations: int

    @property
    def total(self) -> float:
        """Σ a_i."""
        return float(sum(self.armature))

    def to_dict(self) -> dict:
        """The plan as plain Python values."""
        return {
            "robot": self.robot,
            "target": self.target,
            "per_joint": self.per_joint,
            "armature": dict(zip(self.dof_names, self.armature, strict=True)),
            "total": self.total,
            "lower_bound": self.lower_bound,
            "kappa_before": list(self.kappa_before),
            "kappa_after": list(self.kappa_after),
            "qdd_change": list(self.qdd_change),
            "iterations": self.iterations,
        }


def _uniform_lift(Ms: list[np.ndarray], added: np.ndarray, target: float) -> float:
    """Smallest uniform a ≥ 0 with κ(M + diag(added) + aI) ≤ target at every M (closed form)."""
    worst = 0.0
    for M in Ms:
        w = np.linalg.eigvalsh(M + np.diag(added))
        worst = max(worst, (w[-1] - target * w[0]) / (target - 1.0))
    return worst


def _least_total(Ms: list[np.ndarray], target: float, rtol: float) -> tuple[np.ndarray, float, int]:
    def cuts(a: np.ndarray) -> list[tuple[float, np.ndarray]]:
        found = []
        for M in Ms:  # one cut per violated configuration
            w, vectors = np.linalg.eigh(M + np.diag(a))
            g = w[-1] - target * w[0]
            if g > 0:
                found.append((g, vectors[:, -1] ** 2 - target * vectors[:, 0] ** 2))
        return found

    n = Ms[0].shape[0]
    return least_total(cuts, lambda a: _uniform_lift(Ms, a, target), n, rtol)


def least_total(
    cuts: Callable[[np.ndarray], list[tuple[float, np.ndarray]]],
    lift: Callable[[np.ndarray], float],
    n: int,
    rtol: float,
) -> tuple[np.ndarray, float, int]:
    """Least Σ a_i, a ≥ 0, under convex constraints g_k(a) ≤ 0, by Kelley's cutting planes.

    Args:
        cuts: (g_k(a), ∇g_k(a)) of each constraint violated at a (empty when a is feasible).
        lift: The least uniform value that makes a + value feasible (closed form, ≥ 0).
        n: Number of coordinates.
        rtol: Relative gap between the bounds at which to stop.

    Returns:
        The best feasible a found, a lower bound on the least total, and the LPs solved.
    """
    uniform = lift(np.zeros(n))
    best, upper, lower = np.full(n, uniform), n * uniform, 0.0
    if uniform == 0.0:
        return np.zeros(n), 0.0, 0
    rows, rhs = [], []
    a = np.zeros(n)
    for iteration in range(1, MAX_CUTS + 1):
        for g, grad in cuts(a):
            rows.append(grad)
            rhs.append(grad @ a - g)
        lp = linprog(
            np.ones(n), A_ub=np.array(rows), b_ub=np.array(rhs), bounds=[(0, n * uniform)] * n
        )
        if lp.status != 0:  # the uniform point is feasible, so the LP is; a solver failure
            raise ConditioningError(f"the armature LP failed: {lp.message}")
        a, lower = lp.x, max(lower, float(lp.fun))
        lifted = a + lift(a)
        if lifted.sum() < upper:
            best, upper = lifted, float(lifted.sum())
        if upper - lower <= rtol * upper:
            return best, lower, iteration
    return best, lower, MAX_CUTS


def minimal_armature(
    robot: Robot,
    configurations: npt.ArrayLike,
    target: float,
    *,
    per_joint: bool = False,
    rtol: float = 1e-6,
    margin: float = 1e-9,
) -> ArmaturePlan:
    """The smallest armature to add so that κ ≤ ``target`` at every configuration.

    Args:
        robot: A fixed-base robot (armature on a free-flyer's coordinates is not physical).
        configurations: Configurations, shape (K, nq) (or one of length nq).
        target: κ_T > 1.
        per_joint: One value per coordinate minimising the total (cutting planes), instead
            of one uniform value (closed form).
        rtol: Relative optimality gap at which the cutting planes stop (per joint).
        margin: Relative amount the answer is raised so that float64 meets the target
            (finite, ≥ 0).

    Raises:
        InputError: target ≤ 1 or not finite, a negative or NaN margin, a floating base or a
            free joint, no configurations, more than `max_configurations` of them, or bad
            configurations.
    """
    if not 0 < rtol < 1:
        raise InputError("rtol", "in (0, 1)", rtol)
    qs = np.asarray(configurations, dtype=float)
    qs = qs.reshape(0, robot.nq) if qs.size == 0 else np.atleast_2d(qs)
    _check_inputs(robot, qs, target, margin)
    qs = np.array([as_configuration(robot, q) for q in qs])
    model, data = robot.model, robot.new_data()
    Ms = [check_robot_gim(robot, np.array(pin.crba(model, data, q))) for q in qs]
    if per_joint:
        added, lower, iterations = _least_total(Ms, target, rtol)
    else:
        value = _uniform_lift(Ms, np.zeros(robot.nv), target)
        added, lower, iterations = np.full(robot.nv, value), robot.nv * value, 0
    added = added * (1.0 + margin)
    before, after, change = _applied(robot, qs, added)
    return ArmaturePlan(
        robot=robot.name,
        target=float(target),
        per_joint=per_joint,
        dof_names=robot.dof_names,
        armature=tuple(float(x) for x in added),
        lower_bound=float(lower),
        kappa_before=before,
        kappa_after=after,
        qdd_change=change,
        iterations=iterations,
    )


def _applied(
    robot: Robot, qs: np.ndarray, added: np.ndarray
) -> tuple[tuple[float, ...], tuple[float, ...], tuple[float, ...]]:
    """κ before and after, and the relative change of q̈ under gravity, with Pinocchio."""
    model = pin.Model(robot.model)
    data = model.createData()
    armed = pin.Model(robot.model)
    armed.armature = np.asarray(robot.model.armature) + added
    armed_data = armed.createData()
    before: list[float] = []
    after: list[float] = []
    change: list[float] = []
    for q in qs:
        M = np.array(pin.crba(model, data, q))
        MA = np.array(pin.crba(armed, armed_data, q))
        g = pin.computeGeneralizedGravity(model, data, q)
        for matrix, out in ((M, before), (MA, after)):
            w = np.linalg.eigvalsh(matrix)
            out.append(extreme_ratio(w))
        qdd, qdd_armed = np.linalg.solve(M, -g), np.linalg.solve(MA, -g)
        scale = np.linalg.norm(qdd)
        change.append(float(np.linalg.norm(qdd_armed - qdd) / scale) if scale > 0 else 0.0)
    return tuple(before), tuple(after), tuple(change)
