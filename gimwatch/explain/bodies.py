"""The GIM split by body: M = Σ_b J_bᵀ I_b J_b, Jacobians, inertias and names per body.

Pinocchio merges the links fixed to one joint into one body, carried by that joint; body ``b``
here is Pinocchio joint ``b`` (1 ≤ b < njoints) and its name lists the links it holds. The
split is exact: ``M(q) = Σ_b J_bᵀ I_b J_b + diag(armature)`` with ``J_b`` body b's Jacobian and
``I_b`` its 6×6 spatial inertia in the same frame (Featherstone 2008, Eq. 6.12), so every
body's share of the kinetic energy ``½ vᵀ M v`` and every derivative of M with respect to a
body's inertial parameters comes from these pieces without finite differences.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = ["BodySplit", "body_energies", "body_names", "body_split", "dof_joint_ranges"]


def body_names(robot: Robot) -> tuple[str, ...]:
    """Name of each body (Pinocchio joint 1..njoints−1): its links, ``+``-joined, in order.

    A body with no link frame (a bare joint) is named after its joint.
    """
    model = robot.model
    links: list[list[str]] = [[] for _ in range(model.njoints)]
    for frame in model.frames:
        if frame.type == pin.FrameType.BODY and 0 < frame.parentJoint < model.njoints:
            links[frame.parentJoint].append(frame.name)
    return tuple(
        "+".join(links[j]) if links[j] else model.names[j] for j in range(1, model.njoints)
    )


def dof_joint_ranges(robot: Robot) -> list[tuple[str, int, int]]:
    """(joint name, first velocity index, nv) of each moving joint, in Pinocchio's order."""
    model = robot.model
    return [
        (model.names[j], model.joints[j].idx_v, model.joints[j].nv) for j in range(1, model.njoints)
    ]


@dataclass(frozen=True)
class BodySplit:
    """The pieces of ``M(q) = Σ_b J_bᵀ I_b J_b + diag(armature)`` at one configuration.

    Attributes:
        jacobian_local: J_b in body b's frame, shape (nb, 6, nv) ([linear; angular]).
        inertia_local: I_b in body b's frame, shape (nb, 6, 6), SI units.
        jacobian_world: J_b as twists about the world origin, shape (nb, 6, nv).
        inertia_world: I_b about the world origin, world axes, shape (nb, 6, 6).
        parent_rotation: Rotation of each body's parent-joint frame in the world (nb, 3, 3).
        subtree_dofs: Boolean mask (nb, nv): velocity coordinates of the joints in body b's
            subtree (b's own joint included).
        in_subtree: Boolean mask (nb, nb): body c (column) is in the subtree of body b (row).
        armature: The model's armature, one per velocity coordinate.
    """

    jacobian_local: np.ndarray
    inertia_local: np.ndarray
    jacobian_world: np.ndarray
    inertia_world: np.ndarray
    parent_rotation: np.ndarray
    subtree_dofs: np.ndarray
    in_subtree: np.ndarray
    armature: np.ndarray


def body_split(robot: Robot, q: npt.ArrayLike, *, data: pin.Data | None = None) -> BodySplit:
    """Jacobians and spatial inertias of every body at ``q`` (one ``computeJointJacobians``)."""
    model = robot.model
    q = as_configuration(robot, q)
    data = robot.new_data() if data is None else data
    pin.computeJointJacobians(model, data, q)
    nb, nv = model.njoints - 1, model.nv
    jac_local = np.empty((nb, 6, nv))
    jac_world = np.empty((nb, 6, nv))
    inertia_local = np.empty((nb, 6, 6))
    inertia_world = np.empty((nb, 6, 6))
    parent_rotation = np.empty((nb, 3, 3))
    subtree_dofs = np.zeros((nb, nv), dtype=bool)
    in_subtree = np.zeros((nb, nb), dtype=bool)
    for b in range(nb):
        j = b + 1
        jac_world[b] = np.reshape(pin.getJointJacobian(model, data, j, pin.WORLD), (6, nv))
        jac_local[b] = np.reshape(pin.getJointJacobian(model, data, j, pin.LOCAL), (6, nv))
        inertia_local[b] = model.inertias[j].matrix()
        inertia_world[b] = data.oMi[j].act(model.inertias[j]).matrix()
        parent_rotation[b] = data.oMi[model.parents[j]].rotation
        for k in model.subtrees[j]:
            in_subtree[b, k - 1] = True
            start, width = model.joints[k].idx_v, model.joints[k].nv
            subtree_dofs[b, start : start + width] = True
    return BodySplit(
        jacobian_local=jac_local,
        inertia_local=inertia_local,
        jacobian_world=jac_world,
        inertia_world=inertia_world,
        parent_rotation=parent_rotation,
        subtree_dofs=subtree_dofs,
        in_subtree=in_subtree,
        armature=np.array(model.armature, dtype=float),
    )


def body_energies(split: BodySplit, v: npt.ArrayLike) -> np.ndarray:
    """½ (J_b v)ᵀ I_b (J_b v) for each body b: its kinetic energy at joint velocity ``v``."""
    twist = np.einsum("bij,j->bi", split.jacobian_local, np.asarray(v, dtype=float))
    return 0.5 * np.einsum("bi,bij,bj->b", twist, split.inertia_local, twist)
