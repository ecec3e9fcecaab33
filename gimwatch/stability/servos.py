"""The servos that hold a robot: stiffness and damping per coordinate, from MJCF or from gains.

A servo's generalized force is linear near the configuration it holds. For an MJCF file the
actuators are read from MuJoCo's *compiled* model, as MuJoCo computes their force: an affine
actuator (``general`` with ``gaintype`` fixed/affine and ``biastype`` none/affine, which is
what ``position`` and ``velocity`` compile to) on a joint transmission gives

    force = (g0 + g1·l + g2·l̇)·ctrl + b0 + b1·l + b2·l̇,   l = gear·q,   τ = gear·force,

so its stiffness on the coordinate is ``−gear²(b1 + g1·ctrl)`` and its damping
``−gear²(b2 + g2·ctrl)`` (N·m/rad and N·m·s/rad, or N/m and N·s/m). Joint ``stiffness``,
``damping`` and ``armature`` are MuJoCo's ``jnt_stiffness``, ``dof_damping`` and
``dof_armature``. Actuator damping is *explicit* in MuJoCo's ``Euler``; joint damping is
implicit there (``M + h·D``); both are implicit in ``implicitfast`` and ``implicit``.

A URDF, ``chain:N`` or example-robot-data robot has no servos of its own: ``kp`` and ``kd``
(one number, or one per coordinate) give a PD servo on each coordinate (``kd`` explicit).

What the linear model leaves out is named, never silently ignored (`Servos.not_modelled`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from gimwatch.errors import InputError
from gimwatch.model.robots import Robot

__all__ = ["Servos", "gain_servos", "mjcf_servos"]

#: MuJoCo's enums used here (mjtGain, mjtBias, mjtDyn, mjtTrn, mjtJoint).
_GAIN_FIXED, _GAIN_AFFINE = 0, 1
_BIAS_NONE, _BIAS_AFFINE = 0, 1
_TRN_JOINT, _TRN_JOINTINPARENT = 0, 1
_HINGE, _SLIDE = 3, 2


@dataclass(frozen=True)
class Servos:
    """The linear servo model of a robot (Pinocchio's velocity order, length-nv arrays).

    Attributes:
        stiffness: Servo plus joint-spring stiffness per coordinate, ∂τ/∂q negated.
        explicit_damping: Actuator damping per coordinate (explicit in MuJoCo's Euler).
        joint_damping: Joint damping per coordinate (implicit in MuJoCo's Euler).
        actuated: Whether each coordinate has a servo (an actuator or a gain).
        timestep_s: The model's own timestep (MJCF ``<option timestep>``), or None.
        integrator: The model's own integrator (MuJoCo's name), or None.
        not_modelled: What the file has that the linear model leaves out, one short item each.
    """

    stiffness: np.ndarray
    explicit_damping: np.ndarray
    joint_damping: np.ndarray
    actuated: np.ndarray
    timestep_s: float | None = None
    integrator: str | None = None
    not_modelled: tuple[str, ...] = ()


#: MuJoCo's integrator names by mjtIntegrator value.
MUJOCO_INTEGRATORS = ("Euler", "RK4", "implicit", "implicitfast")


def _per_coordinate(name: str, values: float | Sequence[float] | None, robot: Robot) -> np.ndarray:
    """One non-negative finite gain per coordinate, from one number or nv numbers."""
    if values is None:
        return np.zeros(robot.nv)
    array = np.atleast_1d(np.asarray(values, dtype=float))
    if array.ndim != 1 or array.size not in (1, robot.nv):
        raise InputError(
            name, f"one number or {robot.nv} (one per coordinate of {robot.name})", array.size
        )
    bad = ~np.isfinite(array) | (array < 0)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        where = robot.dof_names[k] if array.size == robot.nv else "every coordinate"
        raise InputError(name, f"finite and >= 0 ({where})", float(array[k]))
    return np.broadcast_to(array, (robot.nv,)).astype(float)


def gain_servos(robot: Robot, kp: float | Sequence[float], kd: float | Sequence[float] | None):
    """PD servos ``τ = −kp·(q − q_held) − kd·v`` on every coordinate (kd explicit).

    Raises:
        InputError: A gain of the wrong length, negative, or not finite.
    """
    if robot.free_base:
        raise InputError(
            "the robot", "fixed-base (servos hold joints, not a free base)", robot.name
        )
    stiffness = _per_coordinate("kp", kp, robot)
    damping = _per_coordinate("kd", kd, robot)
    return Servos(
        stiffness=stiffness,
        explicit_damping=damping,
        joint_damping=np.zeros(robot.nv),
        actuated=(stiffness > 0) | (damping > 0),
        not_modelled=("actuator dynamics and saturation",),
    )


def mujoco_dofs(robot: Robot, mj_model) -> np.ndarray:
    """MuJoCo's DoF index of each of the robot's velocity coordinates."""
    dofs: list[int] = []
    for joint_id in robot.mujoco_joints:
        start = int(mj_model.jnt_dofadr[joint_id])
        width = {0: 6, 1: 3}.get(int(mj_model.jnt_type[joint_id]), 1)
        dofs.extend(range(start, start + width))
    return np.array(dofs, dtype=int)


def mjcf_servos(robot: Robot, mj_model, ctrl: npt.ArrayLike) -> Servos:
    """The servos of an MJCF robot as MuJoCo compiled them, holding ``ctrl``.

    Args:
        robot: A robot read from MJCF (its ``mujoco_joints`` map its coordinates).
        mj_model: MuJoCo's compiled model of the same file.
        ctrl: The actuators' controls (affine gains that depend on l or l̇ multiply them).
    """
    if robot.free_base:
        raise InputError(
            "the robot", "fixed-base (servos hold joints, not a free base)", robot.name
        )
    dofs = mujoco_dofs(robot, mj_model)
    where = np.full(mj_model.nv, -1)
    where[dofs] = np.arange(robot.nv)
    n = robot.nv
    stiffness, explicit = np.zeros(n), np.zeros(n)
    actuated = np.zeros(n, dtype=bool)
    skipped: list[str] = []
    ctrl = np.asarray(ctrl, dtype=float)
    for a in range(mj_model.nu):
        name = mj_model.actuator(a).name or f"actuator{a}"
        trn, target = int(mj_model.actuator_trntype[a]), int(mj_model.actuator_trnid[a, 0])
        gain, bias = int(mj_model.actuator_gaintype[a]), int(mj_model.actuator_biastype[a])
        joint_ok = trn in (_TRN_JOINT, _TRN_JOINTINPARENT) and int(mj_model.jnt_type[target]) in (
            _HINGE,
            _SLIDE,
        )
        if (
            not joint_ok
            or gain not in (_GAIN_FIXED, _GAIN_AFFINE)
            or bias
            not in (
                _BIAS_NONE,
                _BIAS_AFFINE,
            )
        ):
            skipped.append(name)
            continue
        k = where[int(mj_model.jnt_dofadr[target])]
        if k < 0:  # a joint outside the robot (another subtree)
            continue
        gear = float(mj_model.actuator_gear[a, 0])
        g, b = mj_model.actuator_gainprm[a], mj_model.actuator_biasprm[a]
        g1, g2 = (float(g[1]), float(g[2])) if gain == _GAIN_AFFINE else (0.0, 0.0)
        b1, b2 = (float(b[1]), float(b[2])) if bias == _BIAS_AFFINE else (0.0, 0.0)
        stiffness[k] -= gear * gear * (b1 + g1 * ctrl[a])
        explicit[k] -= gear * gear * (b2 + g2 * ctrl[a])
        actuated[k] = True
    joint_of_dof = mj_model.dof_jntid[dofs]
    stiffness += mj_model.jnt_stiffness[joint_of_dof]
    return Servos(
        stiffness=stiffness,
        explicit_damping=explicit,
        joint_damping=np.array(mj_model.dof_damping[dofs], dtype=float),
        actuated=actuated,
        timestep_s=float(mj_model.opt.timestep),
        integrator=MUJOCO_INTEGRATORS[int(mj_model.opt.integrator)],
        not_modelled=_not_modelled(mj_model, skipped),
    )


def _not_modelled(mj_model, skipped: list[str]) -> tuple[str, ...]:
    """What the compiled model has that a linearisation at rest leaves out (present only)."""
    items = []
    if (
        mj_model.ngeom
        and mj_model.ngeom > 0
        and np.any(mj_model.geom_contype | mj_model.geom_conaffinity)
    ):
        items.append("contacts")
    if np.any(mj_model.jnt_limited):
        items.append("joint limits")
    if np.any(mj_model.dof_frictionloss > 0):
        items.append("friction loss")
    if mj_model.neq:
        items.append("equality constraints")
    if mj_model.ntendon:
        items.append("tendons")
    if np.any(mj_model.actuator_dyntype != 0):
        items.append("actuator dynamics")
    if np.any(mj_model.actuator_forcelimited) or np.any(mj_model.actuator_ctrllimited):
        items.append("actuator saturation")
    if skipped:
        items.append(f"non-affine or non-joint actuators ({', '.join(skipped)})")
    return tuple(items)
