"""Cross-check of the DeNOC implementation against Pinocchio, robot by robot.

At K seeded random states (q within the joint limits from
[`random_configurations`][gimwatch.model.sampling.random_configurations]; v, a, τ standard
normal from a NumPy generator with the same seed) it compares

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

M(q) is called singular only when numerically rank-deficient, λmin <= nv·ε·λmax (a joint
that moves no mass, redundant coordinates); then q̈ is undefined:
Pinocchio's ABA returns NaN and DeNOC refuses, so only the GIM, τ and the pivots (their
zeros and the NaNs after them must coincide) are compared.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from gimwatch.denoc import DenocModel
from gimwatch.errors import InputError, URDFError
from gimwatch.metrics.conditioning import extreme_ratio, warn_if_ill_conditioned
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.model.denoc_input import instantaneous_urdf
from gimwatch.model.example_robots import EXAMPLE_ROBOT_NOTES
from gimwatch.model.robots import Robot
from gimwatch.model.sampling import (
    placeholder_limit_joints,
    placeholder_note,
    random_configurations,
)

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
        note: Why a quantity was not compared, and which limits were placeholders, or "".
        mujoco_gim_rel_err: Worst error of MuJoCo's ``mj_fullM`` (in Pinocchio's
            coordinates) against ``crba``; None without ``peer="mujoco"``.
        placeholder_limits: Joints whose placeholder limits were replaced by ±π rad / ±1 m.
        mujoco_refusal: Why MuJoCo refused the robot (the link and its reason), or "".
        status: ``"passed"``, ``"failed"``, or ``"not compared"`` when there was nothing to
            compare (M ≡ 0: no moving mass) — never counted as a pass; the reason is in
            ``note``.
    """

    robot: str
    floating: bool
    nv: int
    samples: int
    gim_rel_err: float | None
    gim_diagonal_rel_err: float | None
    tau_rel_err: float | None
    qdd_rel_err: float | None
    qdd_backward_err: float | None
    pivots_rel_err: float | None
    kappa_max: float
    tolerance: float
    passed: bool
    note: str = ""
    mujoco_gim_rel_err: float | None = None
    placeholder_limits: tuple[str, ...] = ()
    mujoco_refusal: str = ""
    status: str = ""

    def __post_init__(self) -> None:
        if not self.status:
            object.__setattr__(self, "status", "passed" if self.passed else "failed")

    def to_dict(self) -> dict:
        """The record as a plain dict (for JSON)."""
        return asdict(self)


def _denoc_at(robot: Robot, q: np.ndarray) -> tuple[DenocModel, np.ndarray]:
    """DeNOC's model of an MJCF tree with balls or several trees at ``q``, and its q."""
    instant = instantaneous_urdf(robot.model, q)
    model = DenocModel.from_urdf(instant.urdf, source=robot.source, joint_order=instant.joint_order)
    return model, instant.q


def check_tolerance(tolerance: float, name: str = "tolerance") -> float:
    """A relative tolerance must be a number in (0, 1): inf or 1 would pass every error."""
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating)):
        raise InputError(name, "a number > 0 and < 1", tolerance)
    if not 0 < tolerance < 1:
        raise InputError(name, "a number > 0 and < 1", tolerance)
    return float(tolerance)


def _worst(current: float, error: float) -> float:
    """The larger error; NaN wins (``max`` would keep 0.0 against NaN), so it never passes."""
    return error if np.isnan(error) or error > current else current


def _finite(robot: Robot, what: str, value: np.ndarray) -> np.ndarray:
    """Refuse a non-finite reference quantity (an overflow in the model) naming the file."""
    if not np.all(np.isfinite(value)):
        raise URDFError(
            robot.source,
            f"Pinocchio's {what} is not finite (inf or NaN): a mass, inertia or length in the "
            "model is too large",
        )
    return value


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


def _singular_joints(robot: Robot, M: np.ndarray) -> str:
    """The joints of the null direction of a rank-deficient M (largest components)."""
    _, vectors = np.linalg.eigh(M)
    null = np.abs(vectors[:, 0])
    dofs = [robot.dof_names[k] for k in np.flatnonzero(null >= 0.1 * null.max())]
    return ", ".join(dofs[:6]) + (", ..." if len(dofs) > 6 else "")


def crosscheck_robot(
    robot: Robot,
    *,
    samples: int = 10,
    seed: int = 0,
    tolerance: float = DEFAULT_TOLERANCE,
    peer: str | None = None,
) -> CrossCheckResult:
    """Compare DeNOC (and MuJoCo) with Pinocchio at ``samples`` seeded random states.

    M(q) is called singular only when it is numerically rank-deficient:
    λ_min(M) <= nv·ε·λ_max(M). Otherwise q̈ is compared within max(tolerance, κ·ε).
    An MJCF model with a ball joint or several floating trees (no URDF DeNOC reads whole) is
    read by DeNOC at each sample with its balls and free joints replaced by one-DoF joints of
    the same motion at that configuration (`gimwatch.model.denoc_input.instantaneous_urdf`):
    M, its diagonal and pivots are compared as for any robot, τ and q̈ at v = 0 (the
    stand-ins' velocity-product terms differ), and ``peer`` defaults to ``"mujoco"``.

    Args:
        robot: The robot (fixed or floating base, as loaded).
        samples: Number of random states, >= 1.
        seed: Seed of the configurations and of v, a, τ.
        tolerance: Largest relative error that passes.
        peer: ``"mujoco"`` to compare MuJoCo's ``mj_fullM`` with ``pinocchio.crba`` too.

    Raises:
        InputError: ``tolerance`` is not a number in (0, 1).
        URDFError: Pinocchio's M(q) is not finite (an overflow in the model).
        MujocoRefusal: MuJoCo refuses an inertia of the robot (the link is named).
    """
    tolerance = check_tolerance(tolerance)
    full_model, full_data = robot.model, robot.new_data()
    model, data = full_model, full_data
    if np.any(np.asarray(full_model.armature)):  # DeNOC's input has no armature: rigid bodies
        model = full_model.copy()
        model.armature = np.zeros(model.nv)
        data = model.createData()
    # An MJCF tree DeNOC cannot read whole is read one configuration at a time.
    per_sample = not robot.urdf_xml and bool(robot.mujoco_joints)
    use_denoc = bool(robot.urdf_xml) or per_sample
    peer = "mujoco" if not use_denoc or (robot.mujoco_joints and peer is None) else peer
    dm = denoc_model(robot, parse=True, rigid=True) if robot.urdf_xml else None
    mj_model, refusal = None, ""
    if peer == "mujoco":
        from gimwatch.model.mujoco_model import MujocoRefusal, compile_robot

        try:
            mj_model = compile_robot(robot)
        except MujocoRefusal as exc:
            if not use_denoc:  # no reference left to compare with
                raise
            refusal = exc.problem
    rng = np.random.default_rng(seed)
    errors = dict.fromkeys(("gim", "diag", "tau", "qdd", "backward", "pivots", "mujoco"), 0.0)
    kappa_max, conditioned_ok, singular_note, largest_entry = 0.0, True, "", 0.0
    for q in random_configurations(robot, samples, seed=seed):
        v, a, tau = (rng.standard_normal(robot.nv) for _ in range(3))
        q_denoc = q
        if per_sample:
            dm, q_denoc = _denoc_at(robot, q)
            v = np.zeros(robot.nv)
        upper = np.triu(pin.crba(model, data, q))
        M_ref = _finite(robot, "mass matrix M(q)", upper + np.triu(upper, 1).T)
        largest_entry = max(largest_entry, float(np.abs(M_ref).max(initial=0.0)))
        eigenvalues = np.linalg.eigvalsh(M_ref)
        rank_deficient = eigenvalues[0] <= robot.nv * _EPS * eigenvalues[-1]
        kappa = np.inf if rank_deficient else extreme_ratio(eigenvalues)
        kappa_max = max(kappa_max, float(kappa))
        if mj_model is not None:
            from gimwatch.model.mujoco_model import pinocchio_mass_matrix

            M_mj = pinocchio_mass_matrix(robot, mj_model, q)
            M_full = M_ref
            if model is not full_model:
                upper = np.triu(pin.crba(full_model, full_data, q))
                M_full = upper + np.triu(upper, 1).T
            errors["mujoco"] = _worst(errors["mujoco"], _relative(M_mj, M_full))
        if rank_deficient and not singular_note:
            singular_note = (
                f"M(q) is singular at a sample (λmin = {eigenvalues[0]:.3g} <= nv·ε·λmax = "
                f"{robot.nv * _EPS * eigenvalues[-1]:.3g}; null direction on "
                f"{_singular_joints(robot, M_ref)}): q̈ is undefined and not compared"
            )
        if dm is None:
            continue
        errors["gim"] = _worst(errors["gim"], _relative(dm.gim(q_denoc), M_ref))
        diagonal = dm.gim_diagonal(q_denoc)
        errors["diag"] = _worst(errors["diag"], _relative(diagonal, np.diag(M_ref)))
        tau_ref = np.array(pin.rnea(model, data, q, v, a))
        tau_denoc = dm.inverse_dynamics(q_denoc, v, a)
        errors["tau"] = _worst(errors["tau"], _relative(tau_denoc, tau_ref))
        pin.crba(model, data, q)
        pin.cholesky.decompose(model, data)
        pivots = dm.forward_dynamics_pivots(q_denoc)
        if rank_deficient:
            pivot_error, met_zero = _pivot_error(pivots, np.array(data.D))
            errors["pivots"] = _worst(errors["pivots"], pivot_error)
            # the pivots before the zero one are held to the tolerance; with no pivot at
            # zero (λmin tiny, not 0) every pivot after the smallest carries κ·ε = ∞ noise
            conditioned_ok &= pivot_error <= tolerance or not met_zero
            continue
        pivot_error = _relative(pivots, np.array(data.D))
        errors["pivots"] = _worst(errors["pivots"], pivot_error)
        allowed = max(tolerance, float(kappa) * _EPS)
        conditioned_ok &= pivot_error <= allowed
        qdd_ref = np.array(pin.aba(model, data, q, v, tau))
        qdd = dm.forward_dynamics(q_denoc, v, tau)
        qdd_error = _relative(qdd, qdd_ref)
        conditioned_ok &= qdd_error <= allowed
        errors["qdd"] = _worst(errors["qdd"], qdd_error)
        backward = np.linalg.norm(M_ref @ (qdd - qdd_ref)) / (
            eigenvalues[-1] * np.linalg.norm(qdd_ref)
        )
        errors["backward"] = _worst(errors["backward"], float(backward))
    notes = []
    vacuous = largest_entry == 0.0
    if vacuous:  # every error is 0 / 1 = 0: nothing was compared, nothing passed
        notes.append(
            f"not compared: M(q) ≡ 0 at all {samples} samples (no link beyond a moving joint "
            "has mass: give the links <inertial> elements)"
        )
    if per_sample:
        notes.append(
            "DeNOC read each sample with the ball and free joints as one-DoF joints of the "
            "same motion at that configuration: τ and q̈ compared at v = 0"
        )
    if not use_denoc:
        for key in ("gim", "diag", "tau", "qdd", "backward", "pivots"):
            errors[key] = None
    elif singular_note:
        errors["qdd"] = errors["backward"] = None
    if refusal:
        notes.append(f"{refusal}; M not compared with MuJoCo")
    if singular_note:
        notes.append(singular_note)
    if robot.spec in EXAMPLE_ROBOT_NOTES:
        notes.append(EXAMPLE_ROBOT_NOTES[robot.spec])
    placeholders = placeholder_limit_joints(robot)
    if placeholders:
        notes.append(placeholder_note(placeholders))
    if mj_model is None:
        errors["mujoco"] = None
    if not singular_note and not vacuous:  # a singular M has its own label in the note
        warn_if_ill_conditioned(kappa_max, where=f"{robot.name} (largest over {samples} samples)")
    compared = [errors[k] for k in ("gim", "diag", "tau", "backward", "mujoco")]
    passed = conditioned_ok and all(e <= tolerance for e in compared if e is not None)
    passed = passed and not any(
        e is not None and np.isnan(e) for e in (*errors.values(), kappa_max)
    )
    return CrossCheckResult(
        robot=robot.name,
        floating=robot.free_base,
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
        passed=bool(passed) and not vacuous,
        note="; ".join(notes),
        mujoco_gim_rel_err=errors["mujoco"],
        placeholder_limits=placeholders,
        mujoco_refusal=refusal,
        status="not compared" if vacuous else "",
    )
