"""The map between MuJoCo's ``qpos``/``qvel`` and gimwatch's q/v for robots read from MJCF.

Pinocchio's joints are MuJoCo's joints in MuJoCo's order (`gimwatch.model.mjcf_compiled`),
so q and qpos have the same length and the same layout, joint by joint:

=========  ==========================  ==========================================
MuJoCo     qpos / qvel                 gimwatch q / v
=========  ==========================  ==========================================
hinge      angle θ / θ̇                 the same (θ is measured as in MuJoCo: θ = ref
                                       is the pose written in the file)
slide      displacement / rate         the same
ball       quaternion (w, x, y, z) /   quaternion (x, y, z, w) / the same angular
           angular velocity, body      velocity
free       position, quaternion        position, quaternion (x, y, z, w) /
           (w, x, y, z) / linear       linear velocity in the *body* frame
           velocity in the *world*     (v_lin = Rᵀ v_world), angular velocity in the
           frame, angular velocity in  body frame
           the body frame
=========  ==========================  ==========================================

With v_mj = T(q) v, MuJoCo's M and gimwatch's are related by M = Tᵀ M_mj T.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from gimwatch.joint_kinds import JointKind, joint_kind

__all__ = ["q_from_qpos", "qpos_from_q", "velocity_map"]


def _quaternion_blocks(model: pin.Model):
    """(idx_q, nq) of each quaternion block (free flyer: after the position; ball)."""
    for joint in model.joints[1:]:
        kind = joint_kind(joint)
        if kind is JointKind.FREE_FLYER:
            yield joint.idx_q + 3
        elif kind is JointKind.SPHERICAL:
            yield joint.idx_q


def qpos_from_q(model: pin.Model, q) -> np.ndarray:
    """MuJoCo's qpos (of the model's joints, MuJoCo's order) from gimwatch's q."""
    qpos = np.array(q, dtype=float)
    for start in _quaternion_blocks(model):
        qpos[start : start + 4] = np.roll(qpos[start : start + 4], 1)
    return qpos


def q_from_qpos(model: pin.Model, qpos) -> np.ndarray:
    """Gimwatch's q from MuJoCo's qpos (quaternions (w, x, y, z) become (x, y, z, w))."""
    q = np.array(qpos, dtype=float)
    for start in _quaternion_blocks(model):
        q[start : start + 4] = np.roll(q[start : start + 4], -1)
    return q


def velocity_map(model: pin.Model, q) -> np.ndarray:
    """T(q) with qvel = T v: identity except a free joint's linear block, its rotation R."""
    T = np.eye(model.nv)
    for joint in model.joints[1:]:
        if joint_kind(joint) is JointKind.FREE_FLYER:
            x, y, z, w = q[joint.idx_q + 3 : joint.idx_q + 7]
            rotation = pin.Quaternion(w, x, y, z).normalized().matrix()
            T[joint.idx_v : joint.idx_v + 3, joint.idx_v : joint.idx_v + 3] = rotation
    return T
