"""Where a watch gets M(q) in a loop gimwatch does not own: MuJoCo, a Pinocchio model, a matrix.

Each source is a [`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource]:
``nv``, ``dof_names``, ``gim(q)`` (the full M) and ``gim_diagonal(q)`` (diag M only, O(n),
no M formed), plus the faster paths it declares (δ in one call, M into the watch's buffer), so
that a metric nobody watches is never paid for.

* [`MujocoSource`][gimwatch.watch.sources.MujocoSource] — M from a MuJoCo
  ``MjModel``/``MjData`` pair. With ``q=None`` it reads the M that MuJoCo already holds in the
  user's ``data`` (``mujoco.mj_fullM``, or the diagonal entries of ``data.M`` alone): no dynamics is
  recomputed. MuJoCo computes M at the start of ``mj_step``, before integrating, so after
  ``mj_step`` it is M at the configuration the step started from; after ``mj_forward`` it is M at
  ``data.qpos``. With ``q`` given (MuJoCo's ``qpos`` layout) M is computed at ``q`` on a private
  ``MjData`` and the user's ``data`` is left untouched.
* [`GivenMatrix`][gimwatch.watch.sources.GivenMatrix] — the M (or diag M) the caller already
  holds.
* [`robot_from_model`][gimwatch.watch.sources.robot_from_model] — a ``pinocchio.Model``
  wrapped as a gimwatch [`Robot`][gimwatch.model.robots.Robot] (M from Pinocchio's CRBA, diag M
  without M).

What MuJoCo's M contains besides the rigid bodies: ``dof_armature`` on the diagonal,
``tendon_armature`` (Jₜᵀ a Jₜ) and ``actuator_armature``; ``armature=False`` removes
``dof_armature`` (and is refused when the model has tendon or actuator armature). Its
coordinates: a free joint's linear velocity is in the world frame and its angular
velocity in the body frame, while Pinocchio's free-flyer has both in the body frame; with
``robot=`` the source maps joints by name into Pinocchio's order and frames (v_mj = T v_pin,
T = R on the linear block, M_pin = Tᵀ M_mj T). The rotation leaves κ, δ and the diagonal
unchanged (the free joint's linear block is m·I in both frames), only the off-diagonal
coupling blocks of M differ.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.joint_kinds import JointKind, joint_kind, joint_type_name
from gimwatch.metrics.conditioning import check_gim
from gimwatch.model.denoc_input import urdf_of_model
from gimwatch.model.mass_matrix_source import (
    CHECK_EVERY_SAMPLE,
    GUARANTEED,
    MassMatrixSource,
)
from gimwatch.model.mjcf_compiled import import_mujoco
from gimwatch.model.mujoco_model import make_mass_matrix
from gimwatch.model.robots import Robot

__all__ = [
    "GivenMatrix",
    "MujocoSource",
    "real_array",
    "robot_from_model",
    "type_name",
]

#: |‖quaternion‖| below this in a free or ball joint's qpos is refused (MuJoCo would
#: normalise a zero quaternion to an arbitrary rotation).
MIN_QUATERNION_NORM = 1e-6


def type_name(value: object) -> str:
    """``module.Class`` of a value, for messages about a wrong type."""
    kind = type(value)
    return f"{kind.__module__}.{kind.__qualname__}"


def real_array(value: npt.ArrayLike, name: str) -> np.ndarray:
    """``value`` as a float array, or an InputError naming ``name`` (complex, text, ragged).

    A complex array is refused rather than cast: the cast drops the imaginary part (NumPy
    only warns), which gives a wrong κ.
    """
    try:
        array = np.asarray(value)
        if array.dtype.kind == "O":  # Python numbers (Fraction, mpmath.mpf, ...)
            return array.astype(float)
    except (TypeError, ValueError) as exc:
        raise InputError(name, "an array of real numbers", str(exc)) from None
    if array.dtype.kind not in "biuf":
        raise InputError(name, "an array of real numbers", f"{array.dtype.name} entries")
    return array.astype(float)


def robot_from_model(model: pin.Model, *, name: str | None = None) -> Robot:
    """A gimwatch `Robot` around a ``pinocchio.Model`` (kept, not copied).

    Raises:
        InputError: ``model`` is not a ``pinocchio.Model``, or has no velocity coordinate.
    """
    if not isinstance(model, pin.Model):
        raise InputError("model", "a pinocchio.Model", type_name(model))
    if model.nv < 1:
        raise InputError("model", "a pinocchio.Model with at least one joint", f"nv = {model.nv}")
    floating = model.njoints > 1 and joint_kind(model.joints[1]) is JointKind.FREE_FLYER
    label = name or model.name or "pinocchio_model"
    return Robot(
        name=label,
        spec="<pinocchio.Model>",
        model=model,
        urdf_xml=urdf_of_model(model),  # DeNOC's compiled O(n) path when it reads the tree
        source="<pinocchio.Model>",
        floating=floating,
    )


class GivenMatrix(MassMatrixSource):
    """The M (or only diag M) a caller holds, as a `MassMatrixSource` (checked when held).

    Args:
        nv: Size of M.
        dof_names: Names of the coordinates (``dof0``, ``dof1``, … when omitted).
    """

    #: What it holds was checked when handed in (finite, symmetric, positive diagonal).
    definiteness = GUARANTEED
    #: ``gim(None)`` is the held M.
    reads_state = True

    def __init__(self, nv: int, dof_names: tuple[str, ...] | None = None) -> None:
        if isinstance(nv, bool) or not isinstance(nv, int | np.integer) or nv < 1:
            raise InputError("nv", "an integer >= 1", nv)
        self.nv = int(nv)
        names = tuple(f"dof{k}" for k in range(self.nv)) if dof_names is None else dof_names
        if len(names) != self.nv:
            raise InputError("dof_names", f"{self.nv} names", len(names))
        self.dof_names = tuple(str(n) for n in names)
        self._M: np.ndarray | None = None
        self._diag: np.ndarray | None = None
        self._positive_ratio: Any = None  # numba's kernel, imported by the first δ asked for

    def hold_matrix(self, matrix: npt.ArrayLike) -> None:
        """Hold M for the next sample; checks it is real, of shape (nv, nv), finite, symmetric.

        Definiteness is checked by the solve that uses M (or by the watch's Cholesky).
        """
        M = real_array(matrix, "M")
        if M.shape != (self.nv, self.nv):
            raise InputError("M", f"a ({self.nv}, {self.nv}) matrix", f"shape {M.shape}")
        if not np.all(np.isfinite(M)):
            i, j = np.argwhere(~np.isfinite(M))[0]
            raise InputError("M", "finite", f"{M[i, j]} at ({i}, {j})")
        self._M, self._diag = check_gim(M), None

    def hold_diagonal(self, diagonal: npt.ArrayLike) -> None:
        """Hold diag M for the next sample; checks its shape, finiteness and sign."""
        d = real_array(diagonal, "the diagonal")
        if d.shape != (self.nv,):
            raise InputError("the diagonal", f"a vector of {self.nv} numbers", f"shape {d.shape}")
        if not np.all(np.isfinite(d) & (d > 0)):
            k = int(np.argmin(np.where(np.isfinite(d), d, -np.inf)))
            raise InputError("the diagonal", "finite and > 0", f"{d[k]} at {k}")
        self._M, self._diag = None, d

    def diagonal_ratio(self, q=None) -> float:
        """δ of the held diagonal; NaN (the watch's checked path) unless all are finite and > 0."""
        if self._positive_ratio is None:
            from gimwatch.watch.kernels import positive_ratio  # numba: only when δ is asked

            self._positive_ratio = positive_ratio
        return self._positive_ratio(self.gim_diagonal())

    def gim(self, q=None) -> np.ndarray:
        """The held M."""
        if self._M is None:
            raise InputError(
                "the sample",
                "a full M for the watched metrics (sample_matrix)",
                "only a diagonal (sample_diagonal)",
            )
        return self._M

    def gim_diagonal(self, q=None) -> np.ndarray:
        """The held diag M (or the diagonal of the held M)."""
        if self._diag is not None:
            return self._diag
        return np.diag(self.gim()).copy()


class MujocoSource(MassMatrixSource):
    """M from a MuJoCo ``MjModel``/``MjData`` pair (see the module docstring).

    Args:
        model: The ``mujoco.MjModel``.
        data: Its ``mujoco.MjData`` (the one the user's loop steps).
        robot: A gimwatch [`Robot`][gimwatch.model.robots.Robot] or ``pinocchio.Model`` of the same
            robot: M is then given in its coordinates (joints mapped by name, free-joint frame
                converted).
            None: MuJoCo's coordinates and joint names.
        armature: Keep MuJoCo's ``dof_armature`` on the diagonal (True) or remove it.

    Raises:
        InputError: Wrong types, ``data`` of another model, joints that do not match.
    """

    #: ``gim(None)`` reads the M held in ``data``: a watch may sample without ``q``.
    reads_state = True

    def __init__(self, model, data, *, robot=None, armature: bool = True) -> None:
        mujoco = import_mujoco("a MuJoCo watch")
        if not isinstance(model, mujoco.MjModel):
            raise InputError("model", "a mujoco.MjModel", type_name(model))
        if not isinstance(data, mujoco.MjData):
            raise InputError("data", "a mujoco.MjData", type_name(data))
        if data.model._address != model._address:
            raise InputError(
                "data",
                "the MjData of this MjModel (mujoco.MjData(model))",
                f"an MjData of another model (nq = {data.qpos.size}, nv = {data.qvel.size})",
            )
        if model.nv < 1:
            raise InputError("model", "a MuJoCo model with at least one degree of freedom", 0)
        self._mujoco, self.model, self.data = mujoco, model, data
        self.nv = int(model.nv)
        self._diag_index = np.asarray(model.M_rowadr + model.M_rownnz - 1, dtype=np.intp)
        extra = bool(np.any(model.tendon_armature)) or bool(
            np.any(model.actuator_armature)  # MuJoCo >= 4 (pyproject)
        )
        if not armature and extra:
            raise InputError(
                "armature=False",
                "used on models without tendon or actuator armature",
                "a model with some",
                hint="only dof_armature can be removed",
            )
        self._armature = None if armature else np.array(model.dof_armature, dtype=float)
        #: Whether M is positive definite by construction; a negative armature may break it,
        #: and then the watch checks M at every sample.
        self.trusted = not np.any(np.asarray(model.dof_armature) < 0)
        self.definiteness = GUARANTEED if self.trusted else CHECK_EVERY_SAMPLE
        joint_type = mujoco.mjtJoint
        quaternion_joints = (model.jnt_type == joint_type.mjJNT_FREE) | (
            model.jnt_type == joint_type.mjJNT_BALL
        )
        starts = model.jnt_qposadr[quaternion_joints] + np.where(
            model.jnt_type[quaternion_joints] == joint_type.mjJNT_FREE, 3, 0
        )
        self._quaternions = np.asarray(starts, dtype=np.intp)[:, None] + np.arange(4)
        from gimwatch.watch.kernels import positive_ratio  # numba: only for a MuJoCo watch

        self._positive_ratio = positive_ratio
        self._own = None
        self._order: np.ndarray | None = None
        self._free: list[tuple[int, int]] = []  # (first linear dof in output, qpos of quat)
        self.dof_names = self._mujoco_dof_names()
        if robot is not None:
            self._map_to(robot)

    # -- coordinates ---------------------------------------------------------------------
    def _mujoco_dof_names(self) -> tuple[str, ...]:
        model, names = self.model, []
        for dof in range(model.nv):
            joint = int(model.dof_jntid[dof])
            name = model.joint(joint).name or f"joint{joint}"
            width = int(np.sum(model.dof_jntid == joint))
            names.append(name if width == 1 else f"{name}[{dof - model.jnt_dofadr[joint]}]")
        return tuple(names)

    def _map_to(self, robot) -> None:
        from gimwatch.model.mjcf_compiled import joint_id

        mujoco, model = self._mujoco, self.model
        if isinstance(robot, pin.Model):
            robot = robot_from_model(robot)
        if not isinstance(robot, Robot):
            raise InputError("robot", "a gimwatch Robot or a pinocchio.Model", type_name(robot))
        if robot.nv != model.nv:
            raise InputError("robot", f"a model with nv = {model.nv} like MuJoCo's", robot.nv)
        free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
        order = np.full(robot.nv, -1, dtype=np.intp)
        for joint, name in zip(robot.model.joints[1:], robot.model.names[1:], strict=True):
            j = joint_id(model, name)
            kind = joint_kind(joint)
            if j < 0 and kind is JointKind.FREE_FLYER and free.size == 1:
                j = int(free[0])  # MuJoCo's free joint often has another name
            if j < 0:
                raise InputError(
                    "robot", "a model whose joints MuJoCo has too (by name)", f"joint '{name}'"
                )
            expected = _mujoco_joint_type(kind)
            if expected is not None and int(model.jnt_type[j]) != expected:
                found = mujoco.mjtJoint(int(model.jnt_type[j])).name.removeprefix("mjJNT_")
                raise InputError(
                    f"joint '{name}'",
                    f"a MuJoCo {_TYPE_NAMES[expected]} joint like the robot's "
                    f"({joint_type_name(joint)})",
                    found.lower(),
                )
            width = 6 if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE else None
            dofs = int(np.sum(model.dof_jntid == j)) if width is None else width
            if dofs != joint.nv:
                raise InputError(f"joint '{name}'", f"{joint.nv} dof in MuJoCo too", dofs)
            start = int(model.jnt_dofadr[j])
            order[joint.idx_v : joint.idx_v + joint.nv] = np.arange(start, start + dofs)
            if kind is JointKind.FREE_FLYER:
                self._free.append((joint.idx_v, int(model.jnt_qposadr[j]) + 3))
        if np.any(order < 0) or np.unique(order).size != order.size:
            raise InputError("robot", "a one-to-one joint match with the MuJoCo model", "none")
        self._order = order
        self.dof_names = robot.dof_names

    # -- M -------------------------------------------------------------------------------
    def _data_at(self, q):
        mujoco, model = self._mujoco, self.model
        if q is None:
            data = self.data
            if data.M[self._diag_index[0]] == 0.0 and not np.any(data.M[self._diag_index]):
                raise InputError(
                    "data",
                    "an MjData holding M",
                    "one that MuJoCo never computed",
                    hint="call mujoco.mj_forward(model, data) or mj_step first",
                )
            return data
        qpos = real_array(q, "q")
        if qpos.shape != (model.nq,):
            raise InputError("q", f"a qpos of {model.nq} numbers (MuJoCo's layout)", qpos.shape)
        if not np.all(np.isfinite(qpos)):
            raise InputError("q", "finite", qpos.tolist())
        if self._quaternions.size:
            norms = np.linalg.norm(qpos[self._quaternions], axis=1)
            if np.any(norms < MIN_QUATERNION_NORM):
                k = int(np.argmin(norms))
                start = int(self._quaternions[k, 0])
                raise InputError(
                    f"the quaternion q[{start}:{start + 4}]", "non-zero", qpos[start : start + 4]
                )
        if self._own is None:
            self._own = mujoco.MjData(model)
        data = self._own
        data.qpos[:] = qpos
        make_mass_matrix(model, data)  # no collision stage: contacts may overflow the arena
        return data

    def gim(self, q=None, out: np.ndarray | None = None) -> np.ndarray:
        """M (``mj_fullM``, into ``out`` if given), in the robot's coordinates if one was given."""
        data = self._data_at(q)
        M = np.empty((self.nv, self.nv)) if out is None else out
        self._mujoco.mj_fullM(self.model, data, M)
        if self._armature is not None:
            M[np.diag_indices(self.nv)] -= self._armature
        if self._order is None:
            return M
        M = M[np.ix_(self._order, self._order)]
        for start, quat in self._free:  # v_mj = R v_pin on the linear block: M <- Tᵀ M T
            R = _rotation(data.qpos[quat : quat + 4])
            lin = slice(start, start + 3)
            M[lin, :] = R.T @ M[lin, :]
            M[:, lin] = M[:, lin] @ R
        return M

    def gim_into(self, q, out: np.ndarray) -> np.ndarray:
        """M written into ``out`` (no allocation when no robot's coordinates are asked for)."""
        return self.gim(q, out=out)

    def gim_diagonal(self, q=None) -> np.ndarray:
        """The diagonal of M from MuJoCo's sparse M, no M formed (the rotation keeps it)."""
        diag = self._data_at(q).M[self._diag_index]
        if self._armature is not None:
            diag = diag - self._armature
        return diag if self._order is None else diag[self._order]

    def diagonal_ratio(self, q=None) -> float:
        """δ = max M_ii / min M_ii; NaN (the watch's checked path) unless all are finite and > 0."""
        diag = self._data_at(q).M[self._diag_index]
        if self._armature is not None:
            diag = diag - self._armature
        return self._positive_ratio(diag)


def _rotation(quaternion_wxyz: np.ndarray) -> np.ndarray:
    w, x, y, z = quaternion_wxyz / np.linalg.norm(quaternion_wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


#: MuJoCo's joint types (mjtJoint) by their numbers, as MJCF names them.
_TYPE_NAMES = {0: "free", 1: "ball", 2: "slide", 3: "hinge"}


def _mujoco_joint_type(kind: JointKind) -> int | None:
    """MuJoCo's joint type (mjtJoint) matching a Pinocchio joint's kind, None if none is known."""
    return _MUJOCO_JOINT_TYPES.get(kind)


# mjJNT_FREE, _BALL, _SLIDE, _HINGE
_MUJOCO_JOINT_TYPES = {
    JointKind.FREE_FLYER: 0,
    JointKind.SPHERICAL: 1,
    JointKind.SPHERICAL_ZYX: 1,
    JointKind.PRISMATIC: 2,
    JointKind.REVOLUTE: 3,
    JointKind.CONTINUOUS: 3,
}
