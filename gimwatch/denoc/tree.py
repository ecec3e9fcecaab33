"""The body tree DeNOC works on, read from URDF text through yourdfpy (no meshes loaded).

Links joined by ``fixed`` joints are merged into one rigid body (the child's inertia is
carried into the parent body's frame), so every body but the root hangs from exactly one
1-DoF joint (revolute, continuous or prismatic). The root body is the URDF's root link: fixed
to the world, or moving on a 6-DoF free-flyer when ``floating``. Bodies are numbered as a
walk from the root reaches them (children by joint name): a parent comes before its children.

A tree made from arrays (`body_tree`, as `gimwatch.metrics.denoc_robot` does from a loaded
robot) may also give any body a free joint (`FREE_KIND`: six DoF relative to its parent,
Pinocchio's free-flyer) or a ball joint (`BALL_KIND`), and hang several trees from a fixed
root (the world): many free bodies, or robots side by side.
"""

from __future__ import annotations

import dataclasses
import io
import logging
import xml.etree.ElementTree as ET
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import numpy.typing as npt

from gimwatch.errors import InputError, URDFError
from gimwatch.model.urdf_text import check_urdf

__all__ = [
    "BALL_KIND",
    "FREE_FLYER_NAME",
    "FREE_KIND",
    "JOINT_KINDS",
    "BodyTree",
    "body_tree",
    "read_body_tree",
]

#: Joint types DeNOC reads, and the code each moving one gets in `BodyTree.kind`.
JOINT_KINDS = {"revolute": 1, "continuous": 2, "prismatic": 3}
#: `BodyTree.kind` of a free joint: q = (x, y, z, qx, qy, qz, qw) of the body in the joint
#: frame, v = (linear, angular velocity) in the body's frame (Pinocchio's free-flyer).
FREE_KIND = 4
#: `BodyTree.kind` of a ball joint: q = (qx, qy, qz, qw), v = the angular velocity in the
#: body's frame (Pinocchio's spherical joint, MuJoCo's ``ball``).
BALL_KIND = 5
_SUPPORTED = (*JOINT_KINDS, "fixed")
#: Name of the 6-DoF root joint, as in Pinocchio's free-flyer models.
FREE_FLYER_NAME = "root_joint"


@dataclass(frozen=True, eq=False)
class BodyTree:
    """Rigid bodies and the joints between them (index 0 is the root body).

    Attributes:
        source: Where the URDF came from (for messages).
        floating: Whether the root body moves on a free-flyer.
        joint_names: Name of the joint above each body (``root_joint`` or ``""`` for the root).
        parent: Parent body of each body, -1 for the root.
        kind: Joint code of each body (0 root, 1 revolute, 2 continuous, 3 prismatic, 4 free,
            5 ball).
        placement_rotation: Joint frame in the parent body's frame at q = 0 (N, 3, 3).
        placement_translation: Joint origin in the parent body's frame (N, 3), m.
        axis: Unit joint axis in the body's frame (N, 3); zero for the root and free joints.
        mass: Body masses (N,), kg.
        com: Centres of mass in the body frame (N, 3), m.
        inertia: Inertia tensors about the centre of mass, body axes (N, 3, 3), kg·m².
        levels: Index arrays of the bodies at depth 1, 2, ... (the root is depth 0).
    """

    source: str
    floating: bool
    joint_names: tuple[str, ...]
    parent: np.ndarray
    kind: np.ndarray
    placement_rotation: np.ndarray
    placement_translation: np.ndarray
    axis: np.ndarray
    mass: np.ndarray
    com: np.ndarray
    inertia: np.ndarray
    levels: tuple[np.ndarray, ...]

    @property
    def size(self) -> int:
        """Number of bodies, root included."""
        return len(self.parent)


def _check_finite(source: str, element: str, what: str, value: npt.ArrayLike) -> np.ndarray:
    value = np.asarray(value, dtype=float)
    if not np.all(np.isfinite(value)):
        raise URDFError(source, f"{what} must be finite, got {value.tolist()}", element=element)
    return value


def _link_inertia(source: str, link) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass, centre of mass and inertia about it, all in the link frame (massless if absent)."""
    inertial = link.inertial
    if inertial is None:
        return 0.0, np.zeros(3), np.zeros((3, 3))
    element = f"link {link.name!r}"
    mass = float(_check_finite(source, element, "mass", inertial.mass or 0.0))
    if mass < 0:
        raise URDFError(source, f"mass must be >= 0, got {mass}", element=element)
    inertia = np.zeros((3, 3)) if inertial.inertia is None else inertial.inertia
    inertia = _check_finite(source, element, "inertia", inertia)
    origin = np.eye(4) if inertial.origin is None else inertial.origin
    origin = _check_finite(source, element, "inertial origin", origin)
    return mass, origin[:3, 3].copy(), origin[:3, :3] @ inertia @ origin[:3, :3].T


def _merge(bodies: list[tuple[float, np.ndarray, np.ndarray]]) -> tuple:
    """Combine rigid parts (mass, com, inertia about com), all in one frame."""
    mass = sum(part[0] for part in bodies)
    if mass == 0:
        return 0.0, np.zeros(3), sum(part[2] for part in bodies)
    com = sum(part[0] * part[1] for part in bodies) / mass
    inertia = np.zeros((3, 3))
    for m, c, i in bodies:
        r = c - com
        inertia += i + m * (r @ r * np.eye(3) - np.outer(r, r))
    return mass, com, inertia


def _load_yourdfpy(root: ET.Element, source: str):
    """The robot yourdfpy reads from the checked ``<robot>`` element, its chatter silenced.

    It is given the element re-serialised as UTF-8 (no XML declaration naming another
    encoding, no comments for lxml to find too big); its log records are dropped and its
    errors re-worded with the file's name.
    """
    import yourdfpy

    text = ET.tostring(root, encoding="utf-8")
    logger = logging.getLogger("yourdfpy")
    disabled, logger.disabled = logger.disabled, True
    try:
        return yourdfpy.URDF.load(
            io.BytesIO(text),
            build_scene_graph=False,
            build_collision_scene_graph=False,
            load_meshes=False,
            load_collision_meshes=False,
        ).robot
    except Exception as exc:  # yourdfpy raises many types on bad input
        raise URDFError(source, f"yourdfpy cannot read it ({exc})") from exc
    finally:
        logger.disabled = disabled


def _joints_by_parent(joints, source: str) -> dict[str, list]:
    """The URDF's joints grouped by parent link; a joint type DeNOC does not read is an error."""
    children: dict[str, list] = {}
    for joint in joints:
        if joint.type not in _SUPPORTED:
            raise URDFError(
                source,
                f"joint type {joint.type!r} is not supported by DeNOC "
                "(revolute, continuous, prismatic or fixed)",
                element=f"joint {joint.name!r}",
            )
        children.setdefault(joint.parent, []).append(joint)
    return children


def _unit_axis(source: str, element: str, axis: npt.ArrayLike) -> np.ndarray:
    """A joint's axis, checked finite and non-zero, normalised."""
    direction = _check_finite(source, element, "axis", axis)
    norm = float(np.linalg.norm(direction))
    if norm == 0:
        raise URDFError(source, f"axis must be non-zero, got {direction.tolist()}", element=element)
    return direction / norm


def read_body_tree(xml: str, *, floating: bool = False, source: str = "<string>") -> BodyTree:
    """Read URDF text into a [`BodyTree`][gimwatch.denoc.BodyTree].

    Raises:
        URDFError: The links do not form a tree, a joint type is not revolute, continuous,
            prismatic or fixed, or a number DeNOC relies on is not finite (or an axis is 0).
    """
    robot = _load_yourdfpy(check_urdf(xml, source, floating=floating), source)
    children = _joints_by_parent(robot.joints, source)
    links = {link.name: link for link in robot.links}
    child_links = {joint.child for joint in robot.joints}
    root_link = next(name for name in links if name not in child_links)

    names = [FREE_FLYER_NAME if floating else ""]
    parent, kind, rotation, translation, axis = [-1], [0], [np.eye(3)], [np.zeros(3)], [np.zeros(3)]
    parts: list[list] = [[]]
    # stack of (link name, body index, link pose in that body's frame as a 4x4)
    stack = [(root_link, 0, np.eye(4))]
    while stack:
        link_name, body, pose = stack.pop()
        mass, com, inertia = _link_inertia(source, links[link_name])
        R = pose[:3, :3]
        parts[body].append((mass, R @ com + pose[:3, 3], R @ inertia @ R.T))
        # reversed so that the stack pops children in name order (depth-first, by name)
        for joint in sorted(children.get(link_name, ()), key=lambda j: j.name, reverse=True):
            element = f"joint {joint.name!r}"
            origin = np.eye(4) if joint.origin is None else joint.origin
            placed = pose @ _check_finite(source, element, "origin", origin)
            if joint.type == "fixed":
                stack.append((joint.child, body, placed))
                continue
            names.append(joint.name)
            parent.append(body)
            kind.append(JOINT_KINDS[joint.type])
            rotation.append(placed[:3, :3])
            translation.append(placed[:3, 3])
            axis.append(_unit_axis(source, element, joint.axis))
            parts.append([])
            stack.append((joint.child, len(parent) - 1, np.eye(4)))
    merged = [_merge(p) for p in parts]
    return body_tree(
        dict(
            source=source,
            floating=floating,
            joint_names=names,
            parent=parent,
            kind=kind,
            placement_rotation=rotation,
            placement_translation=translation,
            axis=axis,
            mass=[m for m, _, _ in merged],
            com=[c for _, c, _ in merged],
            inertia=[i for _, _, i in merged],
        )
    )


def body_tree(fields: Mapping[str, Any]) -> BodyTree:
    """A [`BodyTree`][gimwatch.denoc.BodyTree] from per-body arrays, parents numbered first.

    ``fields`` maps each field of `BodyTree` but ``levels`` (computed here) to its value:
    ``source``, ``floating``, ``joint_names``, ``parent``, ``kind``, ``placement_rotation``,
    ``placement_translation``, ``axis``, ``mass``, ``com``, ``inertia``. Body 0 is the root;
    with ``floating`` False it is the world (its inertia never enters M) and any of its
    children may be the root of a tree of its own, on a free joint (`FREE_KIND`) or not.

    Raises:
        InputError: A field is missing or unknown.
    """
    wanted = [f.name for f in dataclasses.fields(BodyTree) if f.name != "levels"]
    if sorted(fields) != sorted(wanted):
        missing, unknown = sorted(set(wanted) - set(fields)), sorted(set(fields) - set(wanted))
        raise InputError(
            "body_tree fields", f"exactly {wanted}", f"missing {missing}, unknown {unknown}"
        )
    parent = fields["parent"]
    parent_arr = np.array(parent, dtype=np.intp)
    depth = np.zeros(len(parent_arr), dtype=np.intp)
    for i in range(1, len(parent_arr)):  # parents are numbered before their children
        depth[i] = depth[parent_arr[i]] + 1
    order = np.argsort(depth, kind="stable")
    levels = tuple(np.split(order, np.flatnonzero(np.diff(depth[order])) + 1)[1:])
    return BodyTree(
        source=fields["source"],
        floating=fields["floating"],
        joint_names=tuple(fields["joint_names"]),
        parent=parent_arr,
        kind=np.array(fields["kind"], dtype=np.intp),
        placement_rotation=np.array(fields["placement_rotation"], dtype=float).reshape(-1, 3, 3),
        placement_translation=np.array(fields["placement_translation"], dtype=float).reshape(-1, 3),
        axis=np.array(fields["axis"], dtype=float).reshape(-1, 3),
        mass=np.array(fields["mass"], dtype=float),
        com=np.array(fields["com"], dtype=float).reshape(-1, 3),
        inertia=np.array(fields["inertia"], dtype=float).reshape(-1, 3, 3),
        levels=levels,
    )
