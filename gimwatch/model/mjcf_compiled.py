"""MJCF read as MuJoCo reads it: MuJoCo's compiler, then a Pinocchio model of the compiled tree.

MuJoCo's compiler is the definition of MJCF (includes, defaults, inertia from geoms,
``settotalmass``, frames, ``ref``). The file is compiled with ``mujoco.MjSpec`` and the
Pinocchio model is built from the *compiled* ``MjModel`` (body poses, inertias with
``body_iquat``, joint types, axes, positions, ``qpos0``, armature):

* bodies are visited in MuJoCo's order, so Pinocchio's velocity coordinates are MuJoCo's
  DoFs in MuJoCo's order, and each Pinocchio joint carries its MuJoCo joint's name
  (an unnamed joint is called ``joint<id>``);
* a body with several joints gives consecutive Pinocchio joints (massless bodies between
  them, at the joints' anchors); its inertia is appended after the last joint;
* a hinge turns by ``qpos - qpos0`` (``qpos0`` is the joint's ``ref``): its Pinocchio joint
  placement includes the turn by ``-ref``, so Pinocchio's q of a hinge or slide *is*
  MuJoCo's qpos entry;
* ball and free joints: Pinocchio's quaternion is (x, y, z, w), MuJoCo's (w, x, y, z); a
  free joint's linear velocity is in the world frame in MuJoCo, in the body frame in
  Pinocchio (see `gimwatch.model.mjcf_coordinates`);
* bodies without joints are welded to their parent; bodies welded to the world are left out
  (they do not enter M); ``dof_armature`` goes to ``model.armature`` (Pinocchio's CRBA adds
  it to M's diagonal, as ``mj_fullM`` does) unless ``armature=False``.

``body`` restricts the model to the subtree of one body (its ancestors held at ``qpos0``).
"""

from __future__ import annotations

import re
import warnings

import numpy as np
import pinocchio as pin

from gimwatch.errors import InputError, URDFError
from gimwatch.model.captured_output import captured_c_output
from gimwatch.suggest import did_you_mean

__all__ = [
    "MUJOCO_INSTALL",
    "build_pinocchio_model",
    "compile_mjcf",
    "import_mujoco",
    "subtree_joints",
]

#: MuJoCo's joint types (mjtJoint): free, ball, slide, hinge.
FREE, BALL, SLIDE, HINGE = 0, 1, 2, 3


#: The one install hint for MuJoCo, whatever needs it (MJCF files, the peer, a MuJoCo watch).
MUJOCO_INSTALL = "pip install 'gimwatch[mjcf]'"


def import_mujoco(purpose: str = "MJCF reading"):
    """The ``mujoco`` module, or one line saying what needed it and which install brings it."""
    try:
        import mujoco
    except ImportError:
        raise InputError(purpose, f"MuJoCo installed ({MUJOCO_INSTALL})", "not installed") from None
    return mujoco


def compile_mjcf(path: str, *, floating: bool = False):
    """MuJoCo's compiled model of the MJCF file ``path`` (includes resolved by MuJoCo).

    The compile runs in a child process bounded in time and memory
    (`gimwatch.model.mjcf_sandbox`): an MJCF that expands while MuJoCo reads it is refused,
    not waited for.

    Args:
        path: The MJCF file.
        floating: Give the first body of the world a free joint when it has no joint.

    Raises:
        URDFError: MuJoCo refuses the file (its message, with the element, is kept), or the
            compile runs past its time or memory bound.
    """
    from gimwatch.model.mjcf_sandbox import compile_in_child

    import_mujoco()
    return compile_in_child(lambda: _compile(path, floating), str(path), mujoco_message)


def _compile(path: str, floating: bool):
    mujoco = import_mujoco()
    # MuJoCo's warnings go to a handler of ours: its default one prints them and writes
    # MUJOCO_LOG.TXT into the working folder. Its solver's Python warnings on a model that
    # gimwatch then refuses (an axis that cannot be normalised) are not the user's concern.
    previous = mujoco.get_mju_user_warning()
    mujoco.set_mju_user_warning(lambda message: None)
    try:
        with captured_c_output(1), captured_c_output(2), warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            spec = mujoco.MjSpec.from_file(str(path))
            if floating:
                _add_free_joint(spec, path)
            return spec.compile()
    finally:
        mujoco.set_mju_user_warning(previous)


_ELEMENT = re.compile(r"\s*Element (?:name )?'([^']*)'(?:, id \d+)?, line (\d+)\s*$")
_PARSE = re.compile(r"XML parse error \d+: Error=(\w+).*Line number=(\d+)(?:: (.*))?")


def mujoco_message(error: str) -> str:
    """MuJoCo's error text ``error`` on one line, ending with the element and line it names."""
    lines = [line.strip() for line in error.splitlines() if line.strip()]
    text = " ".join(lines).replace("XML Error: ", "").replace("Error: ", "")
    parse = _PARSE.search(text)
    if parse:
        where = f", {parse.group(3)}" if parse.group(3) else ""
        return f"not well-formed XML ({parse.group(1)} at line {parse.group(2)}{where})"
    element = _ELEMENT.search(text)
    if element:
        name = f"element '{element.group(1)}', " if element.group(1) else ""
        text = f"{text[: element.start()]} ({name}line {element.group(2)})"
    return text or " ".join(lines)  # nothing but MuJoCo's prefix: keep it as written


def _add_free_joint(spec, path) -> None:
    body = spec.worldbody.first_body()
    if body is None:
        raise URDFError(str(path), "has no <body> in <worldbody> to put a floating base on")
    if body.first_joint() is not None:
        if any(j.type == 0 for j in body.joints):  # mjJNT_FREE: already floating
            return
        raise URDFError(
            str(path),
            f"its first body '{body.name}' already has a joint, so there is no base body to "
            "float; add a <freejoint/> body around it in the MJCF",
        )
    body.add_freejoint(name="root_joint")


def _body_id(mj_model, body: str, source: str) -> int:
    import mujoco

    index = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_BODY, body)
    if index <= 0:
        names = [
            mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_BODY, b) or ""
            for b in range(1, mj_model.nbody)
        ]
        hint = did_you_mean(body, names).removeprefix("; ")
        raise InputError("body", f"the name of a body of {source}", body, hint=hint)
    return index


def subtree_joints(mj_model, body: str = "", source: str = "") -> list[int]:
    """MuJoCo's joint ids, in MuJoCo's order, of the whole model or of one body's subtree."""
    selected = np.ones(mj_model.nbody, dtype=bool)
    if body:
        root = _body_id(mj_model, body, source)
        selected[:] = False
        for b in range(root, mj_model.nbody):  # bodies are numbered parents first
            selected[b] = b == root or selected[mj_model.body_parentid[b]]
    return [j for j in range(mj_model.njnt) if selected[mj_model.jnt_bodyid[j]]]


def joint_name(mj_model, j: int) -> str:
    """MuJoCo's name of joint ``j``, or ``joint<j>`` for an unnamed joint."""
    import mujoco

    return mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"


def joint_id(mj_model, name: str) -> int:
    """MuJoCo's id of the joint named ``name`` (`joint_name`'s ``joint<j>`` too), else -1."""
    import mujoco

    j = mujoco.mj_name2id(mj_model, mujoco.mjtObj.mjOBJ_JOINT, name)
    digits = name.removeprefix("joint")
    if j < 0 and digits.isdecimal() and digits.isascii() and int(digits) < mj_model.njnt:
        if not mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, int(digits)):
            j = int(digits)  # an unnamed joint, named by its id
    return j


def _se3(quat_wxyz, position) -> pin.SE3:
    w, x, y, z = (float(c) for c in quat_wxyz)
    return pin.SE3(pin.Quaternion(w, x, y, z).normalized().matrix(), np.array(position, float))


def _axis_joint(kind: int, axis: np.ndarray):
    unit = np.flatnonzero(np.abs(axis) == 1.0)
    aligned = unit.size == 1 and np.count_nonzero(axis) == 1 and axis[unit[0]] > 0
    if kind == HINGE:
        if aligned:
            return (pin.JointModelRX, pin.JointModelRY, pin.JointModelRZ)[unit[0]]()
        return pin.JointModelRevoluteUnaligned(axis)
    if aligned:
        return (pin.JointModelPX, pin.JointModelPY, pin.JointModelPZ)[unit[0]]()
    return pin.JointModelPrismaticUnaligned(axis)


def _joint(mj_model, j: int):
    """Pinocchio's joint model for MuJoCo joint ``j``, its placement before and after it."""
    kind = int(mj_model.jnt_type[j])
    anchor = np.array(mj_model.jnt_pos[j], dtype=float)
    if kind == FREE:
        return pin.JointModelFreeFlyer(), pin.SE3.Identity(), pin.SE3.Identity()
    if kind == BALL:
        return pin.JointModelSpherical(), pin.SE3(np.eye(3), anchor), pin.SE3(np.eye(3), -anchor)
    axis = np.array(mj_model.jnt_axis[j], dtype=float)
    ref = float(mj_model.qpos0[mj_model.jnt_qposadr[j]])
    if kind == HINGE:  # MuJoCo turns by qpos - ref about the anchor
        before = pin.SE3(pin.AngleAxis(-ref, axis).matrix(), anchor)
        return _axis_joint(kind, axis), before, pin.SE3(np.eye(3), -anchor)
    return _axis_joint(kind, axis), pin.SE3(np.eye(3), -ref * axis), pin.SE3.Identity()


def build_pinocchio_model(mj_model, *, body: str = "", armature: bool = True, source: str = ""):
    """Pinocchio's model of the compiled MuJoCo model (see the module docstring).

    Returns:
        ``(model, joint_ids)``: the Pinocchio model and the MuJoCo joint id of each of its
        joints (in Pinocchio's order, which is MuJoCo's).
    """
    kept = set(subtree_joints(mj_model, body, source))
    model = pin.Model()
    model.name = "mjcf"
    # Per body: (Pinocchio joint carrying it, its placement in that joint's frame, frame id).
    carrier: list[tuple[int, pin.SE3, int]] = [(0, pin.SE3.Identity(), 0)]
    joint_ids: list[int] = []
    armatures: list[float] = []
    for b in range(1, mj_model.nbody):
        parent_joint, parent_pose, parent_frame = carrier[mj_model.body_parentid[b]]
        first = int(mj_model.body_jntadr[b])
        joints = [j for j in range(first, first + int(mj_model.body_jntnum[b])) if j in kept]
        pose = parent_pose * _se3(mj_model.body_quat[b], mj_model.body_pos[b])
        if joints and mj_model.jnt_type[joints[0]] == FREE:
            pose = pin.SE3.Identity()  # MuJoCo places a free body by its qpos alone
        for j in joints:
            joint_model, before, after = _joint(mj_model, j)
            parent_joint = model.addJoint(
                parent_joint, joint_model, pose * before, joint_name(mj_model, j)
            )
            joint_ids.append(j)
            dofs = slice(int(mj_model.jnt_dofadr[j]), int(mj_model.jnt_dofadr[j]) + joint_model.nv)
            armatures.extend(float(a) for a in mj_model.dof_armature[dofs])
            pose = after
        name = _body_name(mj_model, b)
        frame = model.addBodyFrame(name, parent_joint, pose, parent_frame)
        carrier.append((parent_joint, pose, frame))
        mass = float(mj_model.body_mass[b])
        if parent_joint > 0 and mass > 0:
            inertia = pin.Inertia(
                mass, np.zeros(3), np.diag(np.array(mj_model.body_inertia[b], dtype=float))
            )
            placement = pose * _se3(mj_model.body_iquat[b], mj_model.body_ipos[b])
            model.appendBodyToJoint(parent_joint, inertia, placement)
    model.armature = np.array(armatures) if armature else np.zeros(model.nv)
    return model, tuple(joint_ids)


def _body_name(mj_model, b: int) -> str:
    import mujoco

    return mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_BODY, b) or f"body{b}"
