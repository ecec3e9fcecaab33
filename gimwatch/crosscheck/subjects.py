"""The cross-check's subjects: what is compared with Pinocchio, chosen once per robot.

Each subject has one method, ``compare(q, state, sample, accumulator)``, and names the error
keys it fills. `choose_subjects` picks them from the robot and the ``peer`` option:

* `DenocSubject`: DeNOC's model of the robot's URDF, read once (M, its O(n) diagonal, τ,
  the UDUᵀ pivots and q̈);
* `InstantDenocSubject`: an MJCF tree with balls or several trees, which DeNOC cannot read
  whole, read at each sample with its balls and free joints as one-DoF joints of the same
  motion at that configuration (τ and q̈ compared at v = 0);
* `MujocoPeer`: MuJoCo's ``mj_fullM`` (in Pinocchio's coordinates) against M as loaded.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Protocol

import numpy as np

from gimwatch.crosscheck.accumulator import ErrorAccumulator
from gimwatch.crosscheck.reference import (
    PinocchioReference,
    ReferenceSample,
    pivot_error,
    relative_error,
)
from gimwatch.denoc import DenocModel
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.model.denoc_input import instantaneous_urdf
from gimwatch.model.robots import Robot

__all__ = [
    "DenocSubject",
    "InstantDenocSubject",
    "MujocoPeer",
    "State",
    "Subject",
    "Subjects",
    "choose_subjects",
]

#: The keys a DeNOC subject fills.
DENOC_KEYS: tuple[str, ...] = ("gim", "diag", "tau", "qdd", "backward", "pivots")


@dataclass(frozen=True)
class State:
    """One random state besides q: velocity, acceleration and torque (standard normal)."""

    v: np.ndarray
    a: np.ndarray
    tau: np.ndarray


class Subject(Protocol):
    """What the cross-check compares with the reference at each sample."""

    keys: tuple[str, ...]

    def compare(
        self, q: np.ndarray, state: State, sample: ReferenceSample, acc: ErrorAccumulator
    ) -> None:
        """Compare at configuration ``q`` and report the errors to ``acc``."""


def compare_denoc(
    reference: PinocchioReference,
    dm: DenocModel,
    q_denoc: np.ndarray,
    q: np.ndarray,
    state: State,
    sample: ReferenceSample,
    acc: ErrorAccumulator,
) -> None:
    """DeNOC's M, diagonal, τ, pivots and (M regular) q̈ at one sample, against Pinocchio."""
    acc.add("gim", relative_error(dm.gim(q_denoc), sample.M))
    acc.add("diag", relative_error(dm.gim_diagonal(q_denoc), np.diag(sample.M)))
    tau_ref = reference.inverse_dynamics(q, state.v, state.a)
    acc.add("tau", relative_error(dm.inverse_dynamics(q_denoc, state.v, state.a), tau_ref))
    pivots_ref = reference.pivots(q)
    pivots = dm.forward_dynamics_pivots(q_denoc)
    if sample.rank_deficient:
        error, met_zero = pivot_error(pivots, pivots_ref)
        acc.add("pivots", error)
        # the pivots before the zero one are held to the tolerance; with no pivot at
        # zero (λmin tiny, not 0) every pivot after the smallest carries κ·ε = ∞ noise
        acc.hold(error <= acc.tolerance or not met_zero)
        return
    error = relative_error(pivots, pivots_ref)
    acc.add("pivots", error)
    allowed = acc.allowed(sample)
    acc.hold(error <= allowed)
    qdd_ref = reference.forward_dynamics(q, state.v, state.tau)
    qdd = dm.forward_dynamics(q_denoc, state.v, state.tau)
    qdd_error = relative_error(qdd, qdd_ref)
    acc.hold(qdd_error <= allowed)
    acc.add("qdd", qdd_error)
    backward = np.linalg.norm(sample.M @ (qdd - qdd_ref)) / (
        sample.eigenvalues[-1] * np.linalg.norm(qdd_ref)
    )
    acc.add("backward", float(backward))


class DenocSubject:
    """DeNOC's model of the robot's URDF text, read once (rigid bodies)."""

    keys: tuple[str, ...] = DENOC_KEYS

    def __init__(self, robot: Robot, reference: PinocchioReference) -> None:
        self.model = denoc_model(robot, parse=True, rigid=True)
        self.reference = reference

    def compare(
        self, q: np.ndarray, state: State, sample: ReferenceSample, acc: ErrorAccumulator
    ) -> None:
        """DeNOC against Pinocchio at ``q``."""
        compare_denoc(self.reference, self.model, q, q, state, sample, acc)


class InstantDenocSubject:
    """DeNOC reading an MJCF tree one configuration at a time (balls, several trees)."""

    keys: tuple[str, ...] = DENOC_KEYS
    note = (
        "DeNOC read each sample with the ball and free joints as one-DoF joints of the "
        "same motion at that configuration: τ and q̈ compared at v = 0"
    )

    def __init__(self, robot: Robot, reference: PinocchioReference) -> None:
        self.robot = robot
        self.reference = reference

    def compare(
        self, q: np.ndarray, state: State, sample: ReferenceSample, acc: ErrorAccumulator
    ) -> None:
        """DeNOC's model at ``q`` against Pinocchio, τ and q̈ at v = 0."""
        instant = instantaneous_urdf(self.robot.model, q)
        dm = DenocModel.from_urdf(
            instant.urdf, source=self.robot.source, joint_order=instant.joint_order
        )
        at_rest = State(np.zeros(self.robot.nv), state.a, state.tau)
        compare_denoc(self.reference, dm, instant.q, q, at_rest, sample, acc)


class MujocoPeer:
    """MuJoCo's ``mj_fullM`` in Pinocchio's coordinates, against M as loaded (armature kept)."""

    keys: tuple[str, ...] = ("mujoco",)

    def __init__(self, robot: Robot, reference: PinocchioReference, mj_model: object) -> None:
        self.robot = robot
        self.reference = reference
        self.mj_model = mj_model

    def compare(
        self, q: np.ndarray, state: State, sample: ReferenceSample, acc: ErrorAccumulator
    ) -> None:
        """MuJoCo's M against Pinocchio's at ``q``."""
        from gimwatch.model.mujoco_model import pinocchio_mass_matrix

        M_mj = pinocchio_mass_matrix(self.robot, self.mj_model, q)
        acc.add("mujoco", relative_error(M_mj, self.reference.mass_matrix_as_loaded(q, sample)))


@dataclass(frozen=True)
class Subjects:
    """The subjects chosen for one robot, and what the choice left out.

    Attributes:
        subjects: MuJoCo's peer first (if any), then DeNOC (if it reads the robot).
        refusal: Why MuJoCo refused the robot (DeNOC still compared), or "".
        notes: What the choice changes in the comparison, for the result's note.
    """

    subjects: tuple[Subject, ...]
    refusal: str = ""
    notes: tuple[str, ...] = ()

    @property
    def compared(self) -> set[str]:
        """The error keys some subject fills."""
        return {key for subject in self.subjects for key in subject.keys}


def _denoc_subject(robot: Robot, reference: PinocchioReference) -> Subject | None:
    """DeNOC's subject: the URDF read once, an MJCF tree read per sample, or none."""
    if robot.urdf_xml:
        return DenocSubject(robot, reference)
    if robot.mujoco_joints:  # an MJCF tree DeNOC cannot read whole
        return InstantDenocSubject(robot, reference)
    return None


def choose_subjects(
    robot: Robot, reference: PinocchioReference, peer: str | None = None
) -> Subjects:
    """The subjects of ``robot``'s cross-check: DeNOC when it reads it, MuJoCo when asked.

    MuJoCo is the peer when ``peer="mujoco"``, when DeNOC cannot read the robot, and by
    default for an MJCF model with balls or several trees.

    Raises:
        MujocoRefusal: MuJoCo refuses the robot and DeNOC cannot read it either.
    """
    denoc = _denoc_subject(robot, reference)
    if denoc is None or (robot.mujoco_joints and peer is None):
        peer = "mujoco"
    denocs: tuple[Subject, ...] = (denoc,) if denoc is not None else ()
    notes = (denoc.note,) if isinstance(denoc, InstantDenocSubject) else ()
    if peer != "mujoco":
        return Subjects(denocs, notes=notes)
    from gimwatch.model.mujoco_model import MujocoRefusal, compile_robot

    try:
        mj_peer = MujocoPeer(robot, reference, compile_robot(robot))
    except MujocoRefusal as exc:
        if denoc is None:  # no reference left to compare with
            raise
        return Subjects(denocs, refusal=exc.problem, notes=notes)
    return Subjects((mj_peer, *denocs), notes=notes)
