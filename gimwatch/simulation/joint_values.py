"""Joint-indexed scene values resolved against a robot: numbers, lists, ``{joint = x}`` tables.

Velocity-space values (``v``, damping, stiffness, gains, torques) have one entry per
velocity coordinate (nv); configuration-space values (``q``, spring rest, PD target) are
written in user coordinates (continuous joints by angle, see
[`gimwatch.model.configuration`][gimwatch.model.configuration]). Errors are
[`SceneError`][gimwatch.errors.SceneError] naming the scene file, the key and the joint.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from gimwatch.errors import SceneError
from gimwatch.model.configuration import user_configuration
from gimwatch.model.robots import Robot

__all__ = ["joint_vector"]


def joint_vector(
    robot: Robot,
    values: Any,
    *,
    source: str,
    key: str,
    space: str = "v",
    default: np.ndarray | float = 0.0,
) -> np.ndarray:
    """Resolve a scene's joint-indexed value (number, list, or table by joint name).

    Args:
        robot: The robot whose joint names and sizes apply.
        values: A number (broadcast), a tuple (one per coordinate) or a dict by joint name.
        source: The scene file, for error messages.
        key: The scene key, for error messages.
        space: ``"q"`` (a configuration, length nq, from user coordinates) or ``"v"``
            (length nv).
        default: Value of coordinates a table does not name.

    Raises:
        SceneError: Wrong length, unknown joint name, a multi-coordinate joint named in a
            table, a (cos, sin) pair or quaternion far from unit norm.
    """
    if space == "q":
        base = None if np.ndim(default) == 0 and float(default) == 0.0 else default
        return user_configuration(
            robot,
            values,
            key=key,
            error=lambda k, problem: SceneError(source, k, problem),
            default=None if base is None else np.asarray(base, dtype=float),
        )
    model = robot.model
    out = np.array(np.broadcast_to(np.asarray(default, dtype=float), (model.nv,)))
    if isinstance(values, dict):
        names = list(robot.joint_names)
        for name, value in values.items():
            if name not in names:
                shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
                raise SceneError(
                    source, f"{key}.{name}", f"unknown joint; {robot.name} has {shown}"
                )
            joint = model.joints[model.getJointId(name)]
            if joint.nv != 1:
                raise SceneError(
                    source,
                    f"{key}.{name}",
                    f"joint has {joint.nv} velocity coordinates; give a list instead",
                )
            out[joint.idx_v] = value
        return out
    if isinstance(values, (tuple, list)):
        if len(values) != model.nv:
            raise SceneError(
                source,
                key,
                f"must have {model.nv} values (v-coordinates of {robot.name}), got {len(values)}",
            )
        return np.array(values, dtype=float)
    out[:] = float(values)
    return out
