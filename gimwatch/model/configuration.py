"""Configurations as users write them: angles for continuous joints, unit checks, names.

Pinocchio stores a continuous (unbounded revolute) joint as (cos θ, sin θ) (nq = 2, nv = 1),
a floating base as (x, y, z, qx, qy, qz, qw) (nq = 7, nv = 6) and a spherical joint as a
quaternion (nq = 4, nv = 3). A user writes q in *user coordinates*:

* a number ``x`` — every one-coordinate joint (revolute, prismatic, continuous: its angle)
  at ``x``, every multi-coordinate joint (floating base, spherical, planar) at Pinocchio's
  neutral configuration; ``0.0`` is every angle zero and the neutral base;
* a list — one entry per user coordinate: a continuous joint by its angle θ (rad), a
  planar joint by (x, y, θ), a floating base by its 7 numbers, a spherical joint by its
  quaternion (qx, qy, qz, qw). A list of Pinocchio's nq numbers is accepted too, with each
  continuous joint's (cos θ, sin θ) pair;
* a mapping ``{joint: value}`` — one-coordinate joints by name (a continuous joint by its
  angle); joints not named stay at the default.

For a robot read from MJCF a list is MuJoCo's ``qpos`` (its nq numbers, quaternions as
(w, x, y, z)), mapped by `gimwatch.model.mjcf_coordinates.q_from_qpos`.

Every unit-norm block (a continuous joint's (cos, sin), a quaternion) must have norm 1
within `UNIT_TOLERANCE` and is then normalised; a zero or far-from-unit block is
refused naming the joint. Errors are built by the caller's ``error(key, problem)``, so the
scene reader and the command line name the file, the key and the joint their own way.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pinocchio as pin

from gimwatch.errors import GimwatchError
from gimwatch.joint_kinds import JointKind, joint_kind
from gimwatch.model.mjcf_coordinates import q_from_qpos
from gimwatch.model.robots import Robot

__all__ = [
    "UNIT_TOLERANCE",
    "ConfigurationError",
    "coordinate_kinds",
    "user_configuration",
    "user_size",
]

#: |‖block‖ − 1| allowed for a continuous joint's (cos, sin) or a quaternion given by hand.
UNIT_TOLERANCE = 1e-6

ErrorFactory = Callable[[str, str], GimwatchError]


class ConfigurationError(GimwatchError, ValueError):
    """A configuration a user wrote is wrong: ``key: problem``."""

    def __init__(self, key: str, problem: str) -> None:
        self.key, self.problem = key, problem
        super().__init__(f"{key}: {problem}")


def _kind(joint: pin.JointModel) -> str:
    """'one' (revolute, prismatic), 'continuous', 'planar', 'spherical' or 'free-flyer'."""
    kind = joint_kind(joint)
    if kind in _KIND_WORDS:
        return _KIND_WORDS[kind]
    return "one" if joint.nq == 1 else "other"


_KIND_WORDS = {
    JointKind.FREE_FLYER: "free-flyer",
    JointKind.SPHERICAL: "spherical",  # a quaternion (a ZYX ball's 3 angles are "other")
    JointKind.PLANAR: "planar",
    JointKind.CONTINUOUS: "continuous",
}


def _user_width(joint: pin.JointModel) -> int:
    kind = _kind(joint)
    return {"continuous": 1, "planar": 3}.get(kind, joint.nq)


def user_size(robot: Robot) -> int:
    """Number of user coordinates: nq with one angle per continuous joint (and planar θ)."""
    return sum(_user_width(joint) for joint in robot.model.joints[1:])


def coordinate_kinds(robot: Robot) -> str:
    """What makes q non-Euclidean, for messages: e.g. "continuous joints (cos, sin)"."""
    kinds = {_kind(joint) for joint in robot.model.joints[1:]}
    parts = []
    if "continuous" in kinds:
        parts.append("continuous joints (cos θ, sin θ)")
    if "free-flyer" in kinds:
        parts.append("a floating base (position and unit quaternion)")
    if "spherical" in kinds:
        parts.append("spherical joints (unit quaternion)")
    if "planar" in kinds:
        parts.append("planar joints (x, y, cos θ, sin θ)")
    return " and ".join(parts) or "no non-Euclidean coordinates"


def _unit(block: np.ndarray, joint: str, what: str, key: str, error: ErrorFactory) -> np.ndarray:
    norm = float(np.linalg.norm(block))
    if not abs(norm - 1.0) <= UNIT_TOLERANCE:
        raise error(
            key,
            f"{what} of joint {joint} must have norm 1 (within {UNIT_TOLERANCE:g}), "
            f"got norm {norm:.6g}",
        )
    return block / norm


def _angle_block(kind: str, values: np.ndarray) -> np.ndarray:
    """Pinocchio's q block of a joint from its user coordinates."""
    if kind == "continuous":
        return np.array([np.cos(values[0]), np.sin(values[0])])
    if kind == "planar":
        return np.array([values[0], values[1], np.cos(values[2]), np.sin(values[2])])
    return values


def _check_units(
    robot: Robot, q: np.ndarray, key: str, error: ErrorFactory, *, mujoco: bool = False
) -> np.ndarray:
    """Normalise every unit block of a full-length q, refusing those far from norm 1."""
    model = robot.model
    order = "(qw, qx, qy, qz)" if mujoco else "(qx, qy, qz, qw)"
    for joint, name in zip(model.joints[1:], model.names[1:], strict=True):
        kind, start = _kind(joint), joint.idx_q
        if kind == "continuous":
            q[start : start + 2] = _unit(q[start : start + 2], name, "(cos, sin)", key, error)
        elif kind == "planar":
            q[start + 2 : start + 4] = _unit(
                q[start + 2 : start + 4], name, "(cos, sin)", key, error
            )
        elif kind in ("free-flyer", "spherical"):
            tail = slice(start + joint.nq - 4, start + joint.nq)
            q[tail] = _unit(q[tail], name, f"quaternion {order}", key, error)
    return q


def user_configuration(
    robot: Robot,
    values: Any,
    *,
    key: str,
    error: ErrorFactory = ConfigurationError,
    default: np.ndarray | None = None,
) -> np.ndarray:
    """Pinocchio's q (length nq) from a user's number, list or ``{joint: value}`` mapping.

    Args:
        robot: The robot whose joints apply.
        values: See the module docstring.
        key: Name of what is being read (a scene key, ``--q``), for error messages.
        error: Builds the error to raise from (key, problem).
        default: q of joints a mapping does not name (default: neutral).

    Raises:
        GimwatchError: From ``error``: wrong length, unknown or multi-coordinate joint in a
            mapping, non-finite value, a (cos, sin) pair or quaternion far from unit norm.
    """
    if isinstance(values, Mapping):
        return _from_mapping(robot, values, key, error, default)
    if isinstance(values, (list, tuple, np.ndarray)):
        return _from_sequence(robot, values, key, error)
    q = np.array(pin.neutral(robot.model), dtype=float)
    x = float(values)
    for joint in robot.model.joints[1:]:
        kind = _kind(joint)
        if kind in ("one", "continuous"):
            q[joint.idx_q : joint.idx_q + joint.nq] = _angle_block(kind, np.array([x]))
    return q


def _from_mapping(
    robot: Robot,
    values: Mapping,
    key: str,
    error: ErrorFactory,
    default: np.ndarray | None,
) -> np.ndarray:
    """The q of ``{joint: value}``: one-coordinate joints only, the rest from ``default``."""
    model = robot.model
    q = np.array(pin.neutral(model) if default is None else default, dtype=float)
    for name, value in values.items():
        if not model.existJointName(name) or name == "universe":
            names = list(model.names[1:])
            shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
            raise error(f"{key}.{name}", f"unknown joint; {robot.name} has {shown}")
        joint = model.joints[model.getJointId(name)]
        kind = _kind(joint)
        if kind not in ("one", "continuous"):
            raise error(
                f"{key}.{name}",
                f"joint is a {kind} joint with {joint.nq} coordinates; give q as a list",
            )
        q[joint.idx_q : joint.idx_q + joint.nq] = _angle_block(kind, np.array([value]))
    return q


def _from_sequence(robot: Robot, values: Any, key: str, error: ErrorFactory) -> np.ndarray:
    """The q of a list: MuJoCo's qpos (MJCF), Pinocchio's q, or a value per user coordinate."""
    model = robot.model
    flat = np.asarray(values, dtype=float).ravel()
    if not np.all(np.isfinite(flat)):
        raise error(key, f"must be finite, got {flat.tolist()!r}")
    size = user_size(robot)
    if robot.mujoco_joints:  # MJCF: MuJoCo's qpos, quaternions (w, x, y, z)
        if flat.size != model.nq:
            raise error(key, f"must have {model.nq} values (MuJoCo's qpos), got {flat.size}")
        return _check_units(robot, q_from_qpos(model, flat), key, error, mujoco=True)
    if flat.size == model.nq:  # Pinocchio's own coordinates, unit blocks checked
        return _check_units(robot, flat.copy(), key, error)
    if flat.size != size:
        what = f"q-coordinates of {robot.name}"
        if size != model.nq:
            what += f", continuous joints by angle; or Pinocchio's {model.nq} with (cos θ, sin θ)"
        raise error(key, f"must have {size} values ({what}), got {flat.size}")
    q = np.empty(model.nq)
    offset = 0
    for joint in model.joints[1:]:
        width = _user_width(joint)
        block = flat[offset : offset + width]
        q[joint.idx_q : joint.idx_q + joint.nq] = _angle_block(_kind(joint), block)
        offset += width
    return _check_units(robot, q, key, error)
