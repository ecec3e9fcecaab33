"""A gimwatch robot compiled in MuJoCo, and MuJoCo's M(q) in Pinocchio's coordinates.

MuJoCo (optional extra ``gimwatch[peers]``, imported lazily) is an independent reference
for M(q): its own parser, its own tree and its own CRBA (``mj_fullM`` after the parts of
``mj_forward`` that M needs: ``mj_kinematics``, ``mj_comPos``, ``mj_tendon`` when tendons have
armature, ``mj_makeM``). Collision, constraints and flex state are never computed, so a model
whose contacts overflow its arena (a self-colliding flex at a random pose) still gives M; any
error MuJoCo raises is one line naming the robot.

* URDF robots: the text is passed with ``<visual>``/``<collision>`` removed (meshes are not
  needed for inertia) and one ``<mujoco><compiler .../></mujoco>`` block that keeps the
  inertias exact: no inertia balancing, no mass or inertia bounds (unless ``inertia_floor``
  is given), no fused static bodies. A floating base gets ``<freejoint name="root_joint"/>``
  on the root link (the link Pinocchio's free-flyer moves).
* MJCF robots: the file compiled by MuJoCo as gimwatch read it
  (`gimwatch.model.mjcf_compiled.compile_mjcf`), joints matched by MuJoCo's joint ids
  (`gimwatch.model.mjcf_coordinates` maps the coordinates); when the robot was loaded
  with ``armature=False``, ``dof_armature`` is taken off MuJoCo's diagonal too.

Coordinates are mapped joint by joint, by name: revolute/prismatic angle ↔ hinge/slide;
a continuous joint's (cos θ, sin θ) ↔ hinge angle θ; Pinocchio's quaternion (x, y, z, w)
↔ MuJoCo's (w, x, y, z). MuJoCo's free-joint linear velocity is in the world frame,
Pinocchio's in the base frame: with v_mj = T v_pin (T = R on the linear block), the
reference is M_pin = Tᵀ M_mj T.
"""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET

import numpy as np
import pinocchio as pin

from gimwatch.errors import RobotError
from gimwatch.joint_kinds import JointKind, joint_kind, joint_type_name
from gimwatch.model.captured_output import captured_c_output
from gimwatch.model.mjcf_compiled import import_mujoco
from gimwatch.model.robots import Robot

__all__ = [
    "MujocoRefusal",
    "compile_robot",
    "compile_urdf",
    "make_mass_matrix",
    "mass_matrix",
    "pinocchio_mass_matrix",
]

#: The compiler settings that keep a URDF's inertias exactly as written.
EXACT_COMPILER = (
    'balanceinertia="false" boundmass="0" boundinertia="{floor:g}" inertiafromgeom="false" '
    'fusestatic="false" discardvisual="true" angle="radian"'
)


class MujocoRefusal(RobotError):
    """MuJoCo refuses to compile the robot (an inertia it rejects, named per link)."""

    def __init__(self, spec: str, link: str, reason: str) -> None:
        self.link, self.reason = link, reason
        where = f"link '{link}'" if link else "the model"
        super().__init__(spec, f"MuJoCo refuses {where}: {reason}")


def _refusal(spec: str, exc: Exception) -> MujocoRefusal:
    text = str(exc)
    lines = [line.strip() for line in text.splitlines() if line.strip()]
    reason = lines[0].removeprefix("Error:").strip() if lines else type(exc).__name__
    match = re.search(r"Element name '([^']*)'", text)
    return MujocoRefusal(spec, match.group(1) if match else "", reason)


def compile_urdf(urdf_xml: str, *, floating: bool = False, inertia_floor: float = 0.0, spec=""):
    """Compile URDF text in MuJoCo with exact inertias (see the module docstring).

    Raises:
        MujocoRefusal: MuJoCo rejects an inertia (the link and MuJoCo's reason are kept).
    """
    mujoco = import_mujoco("MuJoCo as a peer")
    root = ET.fromstring(urdf_xml)
    for parent in root.iter():
        for child in list(parent):
            if child.tag in ("visual", "collision", "mujoco"):
                parent.remove(child)
    extension = ET.fromstring(
        f"<mujoco><compiler {EXACT_COMPILER.format(floor=inertia_floor)}/></mujoco>"
    )
    root.insert(0, extension)
    if floating:  # MuJoCo folds a link named "world" into its worldbody; keep it a body
        for element in root.iter():
            for key in ("name", "link"):
                if element.tag in ("link", "parent") and element.get(key) == "world":
                    element.set(key, "world_link")
    try:
        with captured_c_output(1), captured_c_output(2):  # MuJoCo prints its warnings
            model_spec = mujoco.MjSpec.from_string(ET.tostring(root, encoding="unicode"))
            if floating:
                model_spec.worldbody.first_body().add_freejoint(name="root_joint")
            return model_spec.compile()
    except (ValueError, mujoco.FatalError) as exc:
        raise _refusal(spec or "<urdf>", exc) from None


def compile_robot(robot: Robot):
    """The robot's ``mujoco.MjModel`` (URDF or MJCF, floating base as loaded).

    Raises:
        MujocoRefusal: MuJoCo rejects an inertia or the file.
    """
    if not robot.mjcf_xml:
        return compile_urdf(robot.urdf_xml, floating=robot.floating, spec=robot.spec)
    from gimwatch.model.mjcf_compiled import compile_mjcf

    import_mujoco("MuJoCo as a peer")
    mj_model = compile_mjcf(robot.source, floating=robot.floating)
    if mj_model.ntendon:  # MuJoCo adds tendon armature to M; gimwatch leaves it out (warned)
        mj_model.tendon_armature[:] = 0.0
    return mj_model


def _joint_maps(robot: Robot, mj_model, q: np.ndarray, mj_q: np.ndarray, T: np.ndarray) -> None:
    from gimwatch.model.mjcf_compiled import joint_id

    model = robot.model
    for joint, name in zip(model.joints[1:], model.names[1:], strict=True):
        j = joint_id(mj_model, name)
        if j < 0:
            raise RobotError(robot.spec, f"MuJoCo has no joint named '{name}'")
        qa, va = int(mj_model.jnt_qposadr[j]), int(mj_model.jnt_dofadr[j])
        iq, iv, kind = joint.idx_q, joint.idx_v, joint_kind(joint)
        if kind is JointKind.FREE_FLYER:
            mj_q[qa : qa + 3] = q[iq : iq + 3]
            mj_q[qa + 3 : qa + 7] = np.roll(q[iq + 3 : iq + 7], 1)
            rotation = pin.Quaternion(q[iq + 6], *q[iq + 3 : iq + 6]).normalized().matrix()
            T[va : va + 3, iv : iv + 3] = rotation
            T[va + 3 : va + 6, iv + 3 : iv + 6] = np.eye(3)
        elif kind is JointKind.SPHERICAL:
            mj_q[qa : qa + 4] = np.roll(q[iq : iq + 4], 1)
            T[va : va + 3, iv : iv + 3] = np.eye(3)
        elif kind is JointKind.CONTINUOUS:  # (cos, sin)
            mj_q[qa] = np.arctan2(q[iq + 1], q[iq])
            T[va, iv] = 1.0
        elif kind in (JointKind.REVOLUTE, JointKind.PRISMATIC):
            mj_q[qa] = q[iq]
            T[va, iv] = 1.0
        else:
            raise RobotError(
                robot.spec, f"joint '{name}' ({joint_type_name(joint)}) has no MuJoCo counterpart"
            )


def mass_matrix(mj_model, mj_q: np.ndarray, *, spec: str = "<mujoco>") -> np.ndarray:
    """MuJoCo's dense M at ``mj_q``: ``mj_fullM`` after what ``mj_makeM`` reads.

    Kinematics, ``mj_comPos`` (composite inertias in the CoM frame) and, when a tendon has
    armature (its Jᵀ a J enters M), ``mj_tendon``; then ``mj_makeM``. Nothing of collision,
    constraints or flex deformation: they do not enter M and may run out of arena memory.

    Raises:
        RobotError: MuJoCo fails (``mujoco.FatalError`` or another error), named for ``spec``.
    """
    import mujoco

    try:
        data = mujoco.MjData(mj_model)
        data.qpos[:] = mj_q
        make_mass_matrix(mj_model, data)
        M = np.zeros((mj_model.nv, mj_model.nv))
        mujoco.mj_fullM(mj_model, data, M)
    except (mujoco.FatalError, ValueError, RuntimeError, MemoryError) as exc:
        raise RobotError(spec, f"MuJoCo fails computing M: {_first_line(exc)}") from None
    return M


def make_mass_matrix(mj_model, data) -> None:
    """Fill ``data``'s M at ``data.qpos`` with only the stages of ``mj_forward`` M reads.

    Kinematics and ``mj_comPos`` for the composite rigid bodies; ``mj_tendon`` and
    ``mj_transmission`` only when a tendon or an actuator has armature (their Jᵀ a J enters
    M); then ``mj_makeM``. Not ``mj_fwdPosition``: its collision stage allocates from the
    model's arena and fails on a self-colliding flex, and contacts do not enter M.
    """
    import mujoco

    mujoco.mj_kinematics(mj_model, data)
    mujoco.mj_comPos(mj_model, data)
    tendon = mj_model.ntendon and np.any(np.asarray(mj_model.tendon_armature) != 0)
    actuator = np.any(np.asarray(getattr(mj_model, "actuator_armature", ())) != 0)
    if tendon or actuator:
        mujoco.mj_tendon(mj_model, data)
        mujoco.mj_transmission(mj_model, data)
    mujoco.mj_makeM(mj_model, data)


def _first_line(exc: Exception) -> str:
    lines = [line.strip() for line in str(exc).splitlines() if line.strip()]
    return lines[0] if lines else type(exc).__name__


def pinocchio_mass_matrix(robot: Robot, mj_model, q: np.ndarray) -> np.ndarray:
    """MuJoCo's M(q) in Pinocchio's velocity coordinates: Tᵀ M_mj T (see module docstring).

    Raises:
        RobotError: A joint of the robot has no MuJoCo joint of the same name, or the two
            models have different numbers of velocity coordinates.
    """
    if mj_model.nv != robot.nv and not robot.mujoco_joints:
        raise RobotError(robot.spec, f"MuJoCo has nv = {mj_model.nv}, Pinocchio nv = {robot.nv}")
    q = np.asarray(q, dtype=float)
    if robot.mujoco_joints:
        return _mjcf_mass_matrix(robot, mj_model, q)
    mj_q = np.array(mj_model.qpos0, dtype=float)
    T = np.zeros((mj_model.nv, robot.nv))
    _joint_maps(robot, mj_model, q, mj_q, T)
    return T.T @ mass_matrix(mj_model, mj_q, spec=robot.spec) @ T


def _mjcf_mass_matrix(robot: Robot, mj_model, q: np.ndarray) -> np.ndarray:
    """MuJoCo's M restricted to the robot's DoFs (a subtree, or all), in gimwatch's v."""
    from gimwatch.model.mjcf_coordinates import qpos_from_q, velocity_map

    mj_q = np.array(mj_model.qpos0, dtype=float)
    qpos = qpos_from_q(robot.model, q)
    dofs: list[int] = []
    for joint, j in zip(robot.model.joints[1:], robot.mujoco_joints, strict=True):
        start = int(mj_model.jnt_qposadr[j])
        mj_q[start : start + joint.nq] = qpos[joint.idx_q : joint.idx_q + joint.nq]
        dofs.extend(range(int(mj_model.jnt_dofadr[j]), int(mj_model.jnt_dofadr[j]) + joint.nv))
    M = mass_matrix(mj_model, mj_q, spec=robot.spec)[np.ix_(dofs, dofs)]
    if not robot.mjcf_armature:
        M -= np.diag(np.asarray(mj_model.dof_armature, dtype=float)[dofs])
    T = velocity_map(robot.model, q)
    return T.T @ M @ T
