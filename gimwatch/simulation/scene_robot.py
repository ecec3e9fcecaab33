"""The scene's robot and its initial state: ``robot``/``base`` and ``q``/``v`` resolved.

A robot with a joint that moves no mass is refused here, naming the URDF and the joint.

Loading failures become a [`SceneError`][gimwatch.errors.SceneError] on key ``robot``; q is read
in user coordinates (continuous joints by angle, ``q = 0.0``: every angle zero and the
neutral base; see [`gimwatch.model.configuration`][gimwatch.model.configuration]), v in velocity
coordinates.
"""

from __future__ import annotations

import numpy as np

from gimwatch.errors import ConditioningError, GimwatchError, InputError, SceneError
from gimwatch.joint_kinds import length_velocities
from gimwatch.metrics.dense_analysis import check_massless
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import (
    Robot,
    chain_robot,
    load_robot,
    neutral_configuration,
)
from gimwatch.simulation.joint_values import joint_vector

__all__ = ["initial_state", "load_scene_robot"]


def _chain_robot(params: dict, floating: bool) -> Robot:
    # above DATA_NV_LIMIT, fixed or floating, a chain runs on the O(n) denoc backend (no
    # Pinocchio Data), up to the URDF parser's depth (chain_robot checks that)
    options = {k: v for k, v in params.items() if k != "n"}
    return chain_robot(chain_spec(params["n"], **options), floating=floating)


def load_scene_robot(scene) -> Robot:
    """Load the scene's robot; failures become a `SceneError` on key ``robot``."""
    try:
        if scene.robot.chain is not None:
            return _chain_robot(scene.robot.chain, bool(scene.robot.floating))
        floating, mjcf = scene.robot.floating, {}
        if scene.robot.body or not scene.robot.armature:
            mjcf = {"body": scene.robot.body, "armature": scene.robot.armature}
        return load_robot(scene.robot.spec, floating=floating, **mjcf)
    except SceneError:
        raise
    except GimwatchError as exc:
        if isinstance(exc, InputError) and exc.name == "body":  # the scene's own key
            hint = f" ({exc.hint})" if exc.hint else ""
            raise scene.error("body", f"must be {exc.rule}, got {exc.value!r}{hint}") from exc
        raise scene.error("robot", str(exc)) from exc


def initial_state(scene, robot: Robot) -> tuple[np.ndarray, np.ndarray]:
    """(q0, v0): the scene's ``q`` (neutral when absent) and ``v`` resolved on the robot."""
    q0 = neutral_configuration(robot)
    if scene.q is not None:
        q0 = joint_vector(robot, scene.q, source=scene.source, key="q", space="q", default=q0)
    v0 = joint_vector(robot, scene.v, source=scene.source, key="v")
    _check_moving_mass(scene, robot)
    return q0, v0


def _check_moving_mass(scene, robot: Robot) -> None:
    """Refuse a robot with a joint that moves no mass (M singular), naming the joint.

    Forward dynamics would divide by zero at t = 0. Read from the model's inertias (no M is
    formed): a joint whose subtree has no mass, and for a rotation no rotational inertia
    either, has M_kk = 0 at every q.
    """
    model = robot.model
    mass = [float(body.mass) for body in model.inertias]
    rotational = [float(np.abs(body.inertia).sum()) for body in model.inertias]
    for k in range(model.njoints - 1, 0, -1):  # subtree sums, leaves first: O(n)
        parent = model.parents[k]
        mass[parent] += mass[k]
        rotational[parent] += rotational[k]
    diagonal = []
    for k in range(1, model.njoints):
        joint = model.joints[k]
        sliding = length_velocities(joint) == joint.nv  # translates only: mass alone moves
        moves = mass[k] > 0 if sliding else (mass[k] > 0 or rotational[k] > 0)
        diagonal += [1.0 if moves else 0.0] * joint.nv
    try:
        check_massless(np.array(diagonal), robot.dof_names, name=robot.name, source=robot.source)
    except ConditioningError as exc:
        raise scene.error("robot", str(exc)) from exc
