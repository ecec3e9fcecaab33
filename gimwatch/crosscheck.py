"""Cross-check of the DeNOC implementation against Pinocchio, robot by robot.

At K seeded random states (q within the joint limits from
:func:`~gimwatch.model.robots.random_configurations`; v, a, τ standard normal from a NumPy
generator with the same seed) it compares

* the GIM with ``pinocchio.crba`` (and its O(n) diagonal),
* τ with ``pinocchio.rnea``,
* q̈ with ``pinocchio.aba``,
* the UDUᵀ pivots of the tip-to-root recursion with ``pinocchio.cholesky.decompose``'s ``D``,

each by the relative error ``‖x − x_ref‖ / ‖x_ref‖``, keeping the worst over the samples.

q̈ is the solution of ``M q̈ = τ − h``: two backward-stable solvers can differ in it by up to
about κ(M)·ε even when both are right, and so can the pivots eliminated after a tiny one. So
GIM, diagonal and τ (well-conditioned) must agree within the tolerance; for q̈ the normwise
*backward error* ``‖M_ref (q̈ − q̈_ref)‖ / (‖M_ref‖₂ ‖q̈_ref‖)`` must be within the tolerance,
and the forward errors of q̈ and of the pivots within ``max(tolerance, κ₂(M)·ε)`` at each
sample (ε = 2.2e-16), the round-off floor of any backward-stable elimination.

When M(q) is singular (a joint that moves no mass), q̈ is undefined:
Pinocchio's ABA returns NaN and DeNOC refuses, so only the GIM, τ and the pivots (their
zeros and the NaNs after them must coincide) are compared.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from gimwatch.denoc import DenocModel
from gimwatch.model.robots import Robot, random_configurations

__all__ = ["CrossCheckResult", "crosscheck_robot", "denoc_model"]

DEFAULT_TOLERANCE = 1e-10
_EPS = float(np.finfo(float).eps)


@dataclass(frozen=True)
class CrossCheckResult:
    """Worst relative errors of DeNOC against Pinocchio over the samples of one robot.

    Attributes:
        robot: Robot name.
        floating: Whether the base was a free-flyer.
        nv: Number of velocity coordinates.
        samples: Number of random states.
        gim_rel_err: Worst ‖M − M_crba‖ / ‖M_crba‖ (Frobenius).
        gim_diagonal_rel_err: Worst error of DeNOC's O(n) diagonal against diag(M_crba).
        tau_rel_err: Worst error of τ against ``rnea``.
        qdd_rel_err: Worst forward error of q̈ against ``aba``; None when M(q) is singular.
        qdd_backward_err: Worst ‖M_ref (q̈ − q̈_ref)‖ / (‖M_ref‖₂ ‖q̈_ref‖); None when M(q)
            is singular.
        pivots_rel_err: Worst error of the UDUᵀ pivots against ``cholesky.decompose``
            (only those eliminated before a zero one when M is singular; inf if the two
            meet the zero pivot at different coordinates).
        kappa_max: Largest 2-norm condition number of M over the samples (inf if singular).
        tolerance: The tolerance the errors were held to.
        passed: GIM, diagonal, τ and the q̈ backward error within the tolerance; q̈ and
            pivot forward errors within max(tolerance, κ·ε) at every sample.
        note: Why a quantity was not compared, or "".
    """

    robot: str
    floating: bool
    nv: int
    samples: int
    gim_rel_err: float
    gim_diagonal_rel_err: float
    tau_rel_err: float
    qdd_rel_err: float | None
    qdd_backward_err: float | None
    pivots_rel_err: float
    kappa_max: float
    tolerance: float
    passed: bool
    note: str = ""

    def to_dict(self) -> dict:
        """The record as a plain dict (for JSON)."""
        return asdict(self)


def denoc_model(robot: Robot) -> DenocModel:
    """The DeNOC model of a gimwatch robot, its coordinates in Pinocchio's order."""
    return DenocModel.from_urdf(
        robot.urdf_xml, floating=robot.floating, source=robot.source, joint_order=robot.joint_names
    )


def _relative(x: np.ndarray, reference: np.ndarray) -> float:
    scale = float(np.linalg.norm(reference))
    return float(np.linalg.norm(x - reference)) / (scale if scale > 0 else 1.0)


def _pivot_error(pivots: np.ndarray, reference: np.ndarray) -> tuple[float, bool]:
    """Relative error of the pivots, and whether M is singular (a pivot ~0 or not finite).

    UDUᵀ eliminates from the last coordinate; after a zero pivot the rest are undefined
    (NaN, inf or round-off noise), so then only those eliminated before it are compared, and
    both factorisations must meet the zero at the same coordinate (else the error is inf).
    """
    finite = np.concatenate([pivots[np.isfinite(pivots)], reference[np.isfinite(reference)]])
    floor = 100 * pivots.size * _EPS * (np.abs(finite).max() if finite.size else 0.0)
    bad = [np.flatnonzero(~(np.isfinite(x) & (x > floor))) for x in (pivots, reference)]
    if not bad[0].size and not bad[1].size:
        return _relative(pivots, reference), False
    if not (bad[0].size and bad[1].size) or bad[0][-1] != bad[1][-1]:
        return float("inf"), True
    start = bad[0][-1] + 1
    return _relative(pivots[start:], reference[start:]), True


def crosscheck_robot(
    robot: Robot,
    *,
    samples: int = 10,
    seed: int = 0,
    tolerance: float = DEFAULT_TOLERANCE,
) -> CrossCheckResult:
    """Compare DeNOC with Pinocchio at ``samples`` seeded random states of ``robot``.

    Args:
        robot: The robot (fixed or floating base, as loaded).
        samples: Number of random states, >= 1.
        seed: Seed of the configurations and of v, a, τ.
        tolerance: Largest relative error that passes.
    """
    model, data = robot.model, robot.new_data()
    dm = denoc_model(robot)
    rng = np.random.default_rng(seed)
    errors = dict.fromkeys(("gim", "diag", "tau", "qdd", "backward", "pivots"), 0.0)
    kappa_max, singular, conditioned_ok = 0.0, False, True
    for q in random_configurations(robot, samples, seed=seed):
        v, a, tau = (rng.standard_normal(robot.nv) for _ in range(3))
        upper = np.triu(pin.crba(model, data, q))
        M_ref = upper + np.triu(upper, 1).T
        eigenvalues = np.linalg.eigvalsh(M_ref)
        kappa = eigenvalues[-1] / eigenvalues[0] if eigenvalues[0] > 0 else np.inf
        kappa_max = max(kappa_max, float(kappa))
        errors["gim"] = max(errors["gim"], _relative(dm.gim(q), M_ref))
        errors["diag"] = max(errors["diag"], _relative(dm.gim_diagonal(q), np.diag(M_ref)))
        tau_ref = np.array(pin.rnea(model, data, q, v, a))
        errors["tau"] = max(errors["tau"], _relative(dm.inverse_dynamics(q, v, a), tau_ref))
        pin.crba(model, data, q)
        pin.cholesky.decompose(model, data)
        pivots = dm.forward_dynamics_pivots(q)
        pivot_error, singular_here = _pivot_error(pivots, np.array(data.D))
        errors["pivots"] = max(errors["pivots"], pivot_error)
        if singular_here:
            singular = True
            conditioned_ok &= pivot_error <= tolerance  # the pivots before the zero one
            continue
        allowed = max(tolerance, float(kappa) * _EPS)
        conditioned_ok &= pivot_error <= allowed
        qdd_ref = np.array(pin.aba(model, data, q, v, tau))
        qdd = dm.forward_dynamics(q, v, tau)
        qdd_error = _relative(qdd, qdd_ref)
        conditioned_ok &= qdd_error <= allowed
        errors["qdd"] = max(errors["qdd"], qdd_error)
        backward = np.linalg.norm(M_ref @ (qdd - qdd_ref)) / (
            eigenvalues[-1] * np.linalg.norm(qdd_ref)
        )
        errors["backward"] = max(errors["backward"], float(backward))
    note = ""
    if singular:
        errors["qdd"] = errors["backward"] = None
        note = "M(q) is singular (a joint moves no mass): q̈ is undefined and not compared"
    compared = [errors[k] for k in ("gim", "diag", "tau", "backward")]
    passed = conditioned_ok and all(e <= tolerance for e in compared if e is not None)
    return CrossCheckResult(
        robot=robot.name,
        floating=robot.floating,
        nv=robot.nv,
        samples=samples,
        gim_rel_err=errors["gim"],
        gim_diagonal_rel_err=errors["diag"],
        tau_rel_err=errors["tau"],
        qdd_rel_err=errors["qdd"],
        qdd_backward_err=errors["backward"],
        pivots_rel_err=errors["pivots"],
        kappa_max=kappa_max,
        tolerance=tolerance,
        passed=bool(passed),
        note=note,
    )
