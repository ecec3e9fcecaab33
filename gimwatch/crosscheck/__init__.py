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

The check is three objects: the reference (`gimwatch.crosscheck.reference`, Pinocchio), the
subjects chosen once per robot (`gimwatch.crosscheck.subjects`: DeNOC read once or per
sample, MuJoCo's peer) and the accumulator of the worst errors and the verdict
(`gimwatch.crosscheck.accumulator`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from gimwatch.crosscheck.accumulator import CrossCheckResult, ErrorAccumulator
from gimwatch.crosscheck.reference import PinocchioReference, check_tolerance
from gimwatch.crosscheck.subjects import State, Subjects, choose_subjects
from gimwatch.metrics.conditioning import warn_if_ill_conditioned
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.model.example_robots import EXAMPLE_ROBOT_NOTES
from gimwatch.model.robot_spec import RobotSpec
from gimwatch.model.robots import Robot, load_robot
from gimwatch.model.sampling import (
    placeholder_limit_joints,
    placeholder_note,
    random_configurations,
)

__all__ = [
    "DEFAULT_TOLERANCE",
    "CrossCheckResult",
    "check_tolerance",
    "crosscheck_robot",
    "denoc_model",
]

DEFAULT_TOLERANCE = 1e-10


def crosscheck_robot(
    robot: Robot | RobotSpec | str | Path,
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
        robot: The robot (fixed or floating base, as loaded), or its `RobotSpec` or text
            (parsed and loaded once, with the robot's own base).
        samples: Number of random states, >= 1.
        seed: Seed of the configurations and of v, a, τ.
        tolerance: Largest relative error that passes.
        peer: ``"mujoco"`` to compare MuJoCo's ``mj_fullM`` with ``pinocchio.crba`` too.

    Raises:
        InputError: ``tolerance`` is not a number in (0, 1).
        URDFError: Pinocchio's M(q) is not finite (an overflow in the model).
        MujocoRefusal: MuJoCo refuses an inertia of the robot (the link is named).
    """
    if not isinstance(robot, Robot):
        robot = load_robot(robot)
    acc = ErrorAccumulator(check_tolerance(tolerance))
    reference = PinocchioReference(robot)
    chosen = choose_subjects(robot, reference, peer)
    rng = np.random.default_rng(seed)
    for q in random_configurations(robot, samples, seed=seed):
        state = State(*(rng.standard_normal(robot.nv) for _ in range(3)))
        sample = reference.sample(q)
        acc.add_reference(sample, reference)
        for subject in chosen.subjects:
            subject.compare(q, state, sample, acc)
    if not acc.singular_note and not acc.vacuous:  # a singular M has its own label
        warn_if_ill_conditioned(
            acc.kappa_max, where=f"{robot.name} (largest over {samples} samples)"
        )
    return _result(robot, samples, acc, chosen)


def _notes(
    robot: Robot, samples: int, acc: ErrorAccumulator, chosen: Subjects, placeholders: tuple
) -> list[str]:
    """Why a quantity was not compared, how it was read, and which limits were placeholders."""
    notes = []
    if acc.vacuous:  # every error is 0 / 1 = 0: nothing was compared, nothing passed
        notes.append(
            f"not compared: M(q) ≡ 0 at all {samples} samples (no link beyond a moving joint "
            "has mass: give the links <inertial> elements)"
        )
    notes.extend(chosen.notes)
    if chosen.refusal:
        notes.append(f"{chosen.refusal}; M not compared with MuJoCo")
    if acc.singular_note:
        notes.append(acc.singular_note)
    if robot.spec in EXAMPLE_ROBOT_NOTES:
        notes.append(EXAMPLE_ROBOT_NOTES[robot.spec])
    if placeholders:
        notes.append(placeholder_note(placeholders))
    return notes


def _result(
    robot: Robot, samples: int, acc: ErrorAccumulator, chosen: Subjects
) -> CrossCheckResult:
    """The record of one robot's cross-check: worst errors, notes and verdict."""
    errors = acc.final_errors(chosen.compared)
    placeholders = placeholder_limit_joints(robot)
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
        kappa_max=acc.kappa_max,
        tolerance=acc.tolerance,
        passed=acc.passed(errors),
        note="; ".join(_notes(robot, samples, acc, chosen, placeholders)),
        mujoco_gim_rel_err=errors["mujoco"],
        placeholder_limits=placeholders,
        mujoco_refusal=chosen.refusal,
        status="not compared" if acc.vacuous else "",
    )
