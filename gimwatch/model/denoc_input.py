"""DeNOC's input written from a Pinocchio model: its body tree as arrays, or URDF text of it.

`tree_arrays` gives DeNOC's body tree of any model of revolute, prismatic and free joints:
one body per joint, the world as body 0, free joints on any body and several trees (what
`gimwatch.denoc.body_tree` takes). It reads the Model only, never a Data (whose memory
grows as nv³), so it serves the O(n) path at any size.

DeNOC (`gimwatch.denoc`) reads URDF with revolute and prismatic joints on one tree, floating
only by one free joint at the root. `urdf_of_model` writes that URDF for a model DeNOC can
read whole (every configuration), else "".

A ball joint or a free object beside the robot has no URDF joint, but at one configuration
its motion is that of joints URDF has: a ball joint turning by ω (child frame) moves its
child as three revolute joints about the child's x, y and z axes through the joint centre,
at angle 0 and rates ω; a free joint (Pinocchio's free-flyer: v = linear, angular velocity
in the body frame) as three prismatic joints along the body's axes followed by three
revolute ones. The motion subspaces are the same columns, so M(q), gravity and the UDUᵀ
pivots are the same (what DeNOC checks); the velocity-product terms are not (the chained
axes turn with each other), so quantities with v ≠ 0 are not comparable.
`instantaneous_urdf` writes that URDF for one configuration q.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gimwatch.errors import RobotError
from gimwatch.joint_kinds import JointKind, joint_axis, joint_kind, joint_type_name

__all__ = ["InstantaneousURDF", "instantaneous_urdf", "tree_arrays", "urdf_of_model"]

_INERTIA_ENTRIES = {
    "ixx": (0, 0),
    "ixy": (0, 1),
    "ixz": (0, 2),
    "iyy": (1, 1),
    "iyz": (1, 2),
    "izz": (2, 2),
}
# The joints standing in for a ball and a free joint at one configuration, in Pinocchio's
# velocity order (free-flyer: linear then angular).
#: A stand-in joint: (name suffix, URDF joint type, axis index).
_Part = tuple[str, str, int]
_BALL_PARTS: tuple[_Part, ...] = (
    ("rx", "revolute", 0),
    ("ry", "revolute", 1),
    ("rz", "revolute", 2),
)
_FREE_PARTS: tuple[_Part, ...] = (
    ("tx", "prismatic", 0),
    ("ty", "prismatic", 1),
    ("tz", "prismatic", 2),
    *_BALL_PARTS,
)


def _xyz(vector) -> str:
    return " ".join(repr(float(x)) for x in vector)


def _inertial(model: pin.Model, k: int) -> str:
    inertia = model.inertias[k]
    I = inertia.inertia
    moments = " ".join(f'{key}="{float(I[r, c])!r}"' for key, (r, c) in _INERTIA_ENTRIES.items())
    return (
        f'<inertial><origin xyz="{_xyz(inertia.lever)}"/>'
        f'<mass value="{float(inertia.mass)!r}"/><inertia {moments}/></inertial>'
    )


def _origin(placement: pin.SE3) -> str:
    rpy = pin.rpy.matrixToRpy(placement.rotation)
    return f'<origin xyz="{_xyz(placement.translation)}" rpy="{_xyz(rpy)}"/>'


# The one-DoF joints DeNOC reads; a kind's value is its URDF type (a continuous joint: nq = 2)
_ONE_DOF = frozenset({JointKind.REVOLUTE, JointKind.CONTINUOUS, JointKind.PRISMATIC})


def _one_dof_joint(model: pin.Model, k: int, parent: str, child: str) -> str:
    joint = model.joints[k]
    urdf_kind = joint_kind(joint).value
    return (
        f'<joint name="{model.names[k]}" type="{urdf_kind}">'
        f'<parent link="{parent}"/><child link="{child}"/>{_origin(model.jointPlacements[k])}'
        f'<axis xyz="{_xyz(joint_axis(joint))}"/>{_limit(model, joint, urdf_kind)}</joint>'
    )


def _limit(model: pin.Model, joint, urdf_kind: str) -> str:
    if urdf_kind == "continuous":  # no limit; its two numbers are (cos θ, sin θ)
        return ""
    lower, upper = model.lowerPositionLimit[joint.idx_q], model.upperPositionLimit[joint.idx_q]
    return f'<limit lower="{float(lower)!r}" upper="{float(upper)!r}" effort="0" velocity="0"/>'


# `gimwatch.denoc.BodyTree.kind` of each URDF type, and of Pinocchio's free-flyer
_KIND = {"revolute": 1, "continuous": 2, "prismatic": 3}
_FREE_KIND, _BALL_KIND = 4, 5


def tree_arrays(model: pin.Model, *, source: str) -> dict:
    """The fields of DeNOC's body tree of ``model`` (keyword arguments of ``body_tree``).

    Body k is Pinocchio's joint k with its inertia (about its centre of mass, in the joint
    frame); body 0 is the world, fixed (``floating`` False); a free-flyer, gimwatch's or a
    file's own, at the root or not, is a free joint of its body, a spherical joint a ball.

    Raises:
        RobotError: A joint DeNOC has no recursion for (a ball, planar, mimic or composite
            joint), named.
    """
    n = model.njoints
    kind, axis = np.zeros(n, dtype=np.intp), np.zeros((n, 3))
    for k in range(1, n):
        joint, joint_type = model.joints[k], joint_kind(model.joints[k])
        if joint_type is JointKind.FREE_FLYER:
            kind[k] = _FREE_KIND
        elif joint_type is JointKind.SPHERICAL:
            kind[k] = _BALL_KIND
        elif joint_type in _ONE_DOF:
            kind[k] = _KIND[joint_type.value]
            axis[k] = joint_axis(joint)
            axis[k] /= np.linalg.norm(axis[k])
        else:
            raise RobotError(
                source,
                f"joint {model.names[k]!r} ({joint_type_name(joint)}) has no "
                "O(n) DeNOC recursion (revolute, prismatic, ball and free joints only)",
            )
    return {
        "source": source,
        "floating": False,
        "joint_names": ("", *model.names[1:]),
        "parent": list(model.parents),
        "kind": kind,
        "placement_rotation": [model.jointPlacements[k].rotation for k in range(n)],
        "placement_translation": [model.jointPlacements[k].translation for k in range(n)],
        "axis": axis,
        "mass": [model.inertias[k].mass for k in range(n)],
        "com": [model.inertias[k].lever for k in range(n)],
        "inertia": [model.inertias[k].inertia for k in range(n)],
    }


def urdf_of_model(model: pin.Model) -> str:
    """URDF text of a Pinocchio model for DeNOC, or "" when DeNOC cannot read the tree.

    DeNOC reads revolute, continuous and prismatic joints on one tree (any number of branches
    on a fixed base), and a floating base only as the one free joint, at the root; for ball
    joints and several floating trees see `instantaneous_urdf`.
    Each joint's placement becomes its ``<origin>``, each joint's inertia its link's
    ``<inertial>`` (about the centre of mass, in the joint frame).
    """
    kinds = [joint_kind(joint) for joint in model.joints[1:]]
    free = [k for k, kind in enumerate(kinds) if kind is JointKind.FREE_FLYER]
    roots = [k for k in range(1, model.njoints) if model.parents[k] == 0]
    if any(kind not in _ONE_DOF for kind in kinds if kind is not JointKind.FREE_FLYER):
        return ""  # a ball, planar, composite or mimic joint: no URDF joint DeNOC reads
    if free not in ([], [0]):
        return ""
    if free and roots != [1]:  # a free object beside a floating robot: two trees
        return ""
    start = 2 if free else 1
    names = {0: "base_link", 1: "base_link"} if free else {0: "base_link"}
    lines = ['<robot name="mjcf">']
    if not free:
        lines.append('<link name="base_link"/>')
    for k in range(1, model.njoints):
        link = names[k] if k < start else f"link_{k}"
        names[k] = link
        lines.append(f'<link name="{link}">{_inertial(model, k)}</link>')
        if k >= start:
            lines.append(_one_dof_joint(model, k, names[model.parents[k]], link))
    lines.append("</robot>")
    return "\n".join(lines)


@dataclass(frozen=True)
class InstantaneousURDF:
    """DeNOC's input for one configuration of any Pinocchio tree (see the module docstring).

    Attributes:
        urdf: URDF text on a fixed base; balls and free joints as 3 and 6 one-DoF joints.
        joint_order: Its moving joints in Pinocchio's velocity order (``nv`` names).
        q: Its configuration (one number per joint, 0 for the stand-ins), rad or m.
    """

    urdf: str
    joint_order: tuple[str, ...]
    q: np.ndarray


def instantaneous_urdf(model: pin.Model, q: np.ndarray) -> InstantaneousURDF:
    """DeNOC's input for ``model`` at ``q``: balls and free joints by their stand-ins.

    Only revolute, prismatic, spherical and free-flyer joints are read (what
    `gimwatch.model.mjcf_compiled.build_pinocchio_model` builds); the stand-ins of a ball
    or free joint take its place at ``q`` (its transform folded into their origin), at angle
    and offset 0.
    """
    q = np.asarray(q, dtype=float)
    lines = ['<robot name="mjcf">', '<link name="base_link"/>']
    names: dict[int, str] = {0: "base_link"}
    order: list[str] = []
    q_out: list[float] = []
    for k in range(1, model.njoints):
        joint, kind, name = model.joints[k], joint_kind(model.joints[k]), model.names[k]
        link = f"link_{k}"
        names[k] = link
        parent = names[model.parents[k]]
        if kind not in (JointKind.SPHERICAL, JointKind.FREE_FLYER):
            lines.append(f'<link name="{link}">{_inertial(model, k)}</link>')
            lines.append(_one_dof_joint(model, k, parent, link))
            order.append(name)
            q_out.extend(q[joint.idx_q : joint.idx_q + joint.nq])  # (cos θ, sin θ) if continuous
            continue
        coordinates = q[joint.idx_q : joint.idx_q + joint.nq]
        if kind is JointKind.FREE_FLYER:
            motion = pin.XYZQUATToSE3(coordinates)
            parts = _FREE_PARTS
        else:
            x, y, z, w = coordinates
            motion = pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.zeros(3))
            parts = _BALL_PARTS
        origin = _origin(model.jointPlacements[k] * motion)
        for p, (suffix, part_kind, axis) in enumerate(parts):
            last = p == len(parts) - 1
            child = link if last else f"{link}__{suffix}"
            inertial = _inertial(model, k) if last else ""  # the stand-ins between: massless
            lines.append(f'<link name="{child}">{inertial}</link>')
            lines.append(
                f'<joint name="{name}__{suffix}" type="{part_kind}">'
                f'<parent link="{parent}"/><child link="{child}"/>'
                f'{origin if p == 0 else ""}<axis xyz="{_xyz(np.eye(3)[axis])}"/>'
                '<limit lower="-1" upper="1" effort="0" velocity="0"/></joint>'
            )
            order.append(f"{name}__{suffix}")
            q_out.append(0.0)
            parent = child
    lines.append("</robot>")
    return InstantaneousURDF("\n".join(lines), tuple(order), np.array(q_out))
