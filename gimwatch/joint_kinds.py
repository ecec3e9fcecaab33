"""What kind of joint a Pinocchio joint model is: one answer for every module that asks.

Pinocchio names its joint types by C++ class (``JointModelRX``, ``JointModelRUBZ``,
``JointModelPrismaticUnaligned``, ...). Tests on those names by substring disagree at the
edges (``"P"`` matches ``Planar``, ``"Spherical"`` matches ``SphericalZYX``), so gimwatch reads
the name once, here, into a `JointKind`, and asks the kind what it needs: the unit-norm block
of q, how many coordinates of q and v are lengths (m) rather than angles (rad), the axis of a
one-axis joint.
"""

from __future__ import annotations

import enum

import numpy as np
import pinocchio as pin

__all__ = [
    "JointKind",
    "joint_axis",
    "joint_kind",
    "joint_type_name",
    "length_positions",
    "length_velocities",
]


class JointKind(enum.Enum):
    """The kinds of joint Pinocchio builds; the value is the URDF type where URDF has one."""

    REVOLUTE = "revolute"  # RX, RY, RZ, RevoluteUnaligned: nq = nv = 1, rad
    CONTINUOUS = "continuous"  # RUBX/Y/Z, RevoluteUnboundedUnaligned: q = (cos θ, sin θ), nv = 1
    PRISMATIC = "prismatic"  # PX, PY, PZ, PrismaticUnaligned: nq = nv = 1, m
    HELICAL = "helical"  # HX, HY, HZ, HelicalUnaligned: nq = nv = 1, the angle in rad
    SPHERICAL = "spherical"  # a ball: q a unit quaternion (x, y, z, w), nv = 3
    SPHERICAL_ZYX = "spherical_zyx"  # a ball in ZYX Euler angles: nq = nv = 3, rad
    FREE_FLYER = "free_flyer"  # (x, y, z, qx, qy, qz, qw), v = (linear, angular)
    PLANAR = "planar"  # (x, y, cos θ, sin θ), v = (vx, vy, ω)
    TRANSLATION = "translation"  # nq = nv = 3, m
    UNIVERSAL = "universal"  # two revolute axes: nq = nv = 2, rad
    ELLIPSOID = "ellipsoid"
    COMPOSITE = "composite"
    MIMIC = "mimic"
    OTHER = "other"  # a joint type this table does not know yet

    @property
    def one_axis(self) -> bool:
        """Whether the joint moves along or about one axis (one velocity coordinate)."""
        return self in _ONE_AXIS

    @property
    def unit_block(self) -> int:
        """Size of the unit-norm tail of its q: 4 (quaternion), 2 (cos, sin) or 0."""
        return _UNIT_BLOCK.get(self, 0)


_ONE_AXIS = frozenset(
    {JointKind.REVOLUTE, JointKind.CONTINUOUS, JointKind.PRISMATIC, JointKind.HELICAL}
)
_UNIT_BLOCK = {
    JointKind.SPHERICAL: 4,
    JointKind.FREE_FLYER: 4,
    JointKind.CONTINUOUS: 2,
    JointKind.PLANAR: 2,
}

# Pinocchio's class name without "JointModel" -> kind; aligned one-axis joints end in X, Y, Z
_BY_NAME = {
    **{f"R{a}": JointKind.REVOLUTE for a in "XYZ"},
    "RevoluteUnaligned": JointKind.REVOLUTE,
    **{f"RUB{a}": JointKind.CONTINUOUS for a in "XYZ"},
    "RevoluteUnboundedUnaligned": JointKind.CONTINUOUS,
    **{f"P{a}": JointKind.PRISMATIC for a in "XYZ"},
    "PrismaticUnaligned": JointKind.PRISMATIC,
    **{f"H{a}": JointKind.HELICAL for a in "XYZ"},
    "HelicalUnaligned": JointKind.HELICAL,
    "Spherical": JointKind.SPHERICAL,
    "SphericalZYX": JointKind.SPHERICAL_ZYX,
    "FreeFlyer": JointKind.FREE_FLYER,
    "Planar": JointKind.PLANAR,
    "Translation": JointKind.TRANSLATION,
    "Universal": JointKind.UNIVERSAL,
    "Ellipsoid": JointKind.ELLIPSOID,
    "Composite": JointKind.COMPOSITE,
    "Mimic": JointKind.MIMIC,
}


def joint_type_name(joint: pin.JointModel) -> str:
    """Pinocchio's name of the joint's type without ``JointModel``: ``RX``, ``Planar``, ..."""
    return str(joint.shortname()).removeprefix("JointModel")


def joint_kind(joint: pin.JointModel) -> JointKind:
    """The kind of a Pinocchio joint model (generic or typed), `JointKind.OTHER` if unknown."""
    return _BY_NAME.get(joint_type_name(joint), JointKind.OTHER)


def joint_axis(joint: pin.JointModel) -> np.ndarray:
    """The axis (a 3-vector in the joint frame) of a one-axis joint.

    Raises:
        ValueError: The joint is not a revolute, continuous, prismatic or helical joint.
    """
    kind = joint_kind(joint)
    if not kind.one_axis:
        raise ValueError(f"a {joint_type_name(joint)} joint has no single axis")
    data = joint.createData()
    joint.calc(data, np.array([1.0, 0.0]) if joint.nq == 2 else np.zeros(1))  # neutral q
    column = np.array(data.S, dtype=float).reshape(6)  # (linear; angular), joint frame
    return column[:3] if kind is JointKind.PRISMATIC else column[3:]


def length_positions(joint: pin.JointModel) -> int:
    """How many of the joint's q coordinates are lengths (m); they come first in its block."""
    kind = joint_kind(joint)
    if kind in (JointKind.PRISMATIC, JointKind.TRANSLATION):
        return int(joint.nq)
    return {JointKind.FREE_FLYER: 3, JointKind.PLANAR: 2}.get(kind, 0)


def length_velocities(joint: pin.JointModel) -> int:
    """How many of the joint's v coordinates are lengths (m/s); they come first in its block.

    The others are angles (rad/s). A free-flyer's v is (linear, angular), a planar
    joint's (vx, vy, ω).
    """
    kind = joint_kind(joint)
    if kind in (JointKind.PRISMATIC, JointKind.TRANSLATION):
        return int(joint.nv)
    return {JointKind.FREE_FLYER: 3, JointKind.PLANAR: 2}.get(kind, 0)
