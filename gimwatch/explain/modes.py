"""The modes behind κ: which joints the eigenvectors of λmin and λmax move, which bodies they load.

For a configuration q with ``M v = λ v`` (unit v):

* participation of joint j: ``Σ_{i ∈ j} v_i²`` over its velocity coordinates; they sum to 1;
* energy share of body b: ``½ (J_b v)ᵀ I_b (J_b v) / ½ vᵀ (M − diag(a)) v``, body b's part of
  the mode's kinetic energy (``M = Σ_b J_bᵀ I_b J_b + diag(a)``, see
  `gimwatch.explain.bodies`); the shares sum to 1, and the armature's part
  ``vᵀ diag(a) v / vᵀ M v`` is reported apart.

λmin's mode is the motion M resists least (a light distal body moved alone), λmax's the one it
resists most (usually the whole arm about its base): κ is their ratio.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.explain.bodies import body_energies, body_names, body_split, dof_joint_ranges
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.dense_analysis import check_robot_gim
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = ["GimModes", "Mode", "gim_modes"]


@dataclass(frozen=True)
class Mode:
    """One eigenpair of M(q), explained.

    Attributes:
        eigenvalue: λ (SI units of M: kg·m² for revolute coordinates).
        vector: The unit eigenvector, one entry per velocity coordinate (sign as LAPACK's).
        joints: (joint, participation) pairs, largest first; participations sum to 1.
        bodies: (body, energy share) pairs, largest first; shares sum to 1.
        armature_share: vᵀ diag(a) v / λ, the part of the mode's energy in the armature.
    """

    eigenvalue: float
    vector: tuple[float, ...]
    joints: tuple[tuple[str, float], ...]
    bodies: tuple[tuple[str, float], ...]
    armature_share: float

    def to_dict(self) -> dict:
        """The mode as plain Python values (pairs as ``{name: value}``, order kept)."""
        return {
            "eigenvalue": self.eigenvalue,
            "vector": list(self.vector),
            "joints": dict(self.joints),
            "bodies": dict(self.bodies),
            "armature_share": self.armature_share,
        }


@dataclass(frozen=True)
class GimModes:
    """The λmin and λmax modes of M(q).

    Attributes:
        robot: Robot name.
        q: The configuration.
        kappa: κ = λmax/λmin.
        lowest: λmin's mode.
        highest: λmax's mode.
    """

    robot: str
    q: tuple[float, ...]
    kappa: float
    lowest: Mode
    highest: Mode

    def to_dict(self) -> dict:
        """The record as plain Python values."""
        return {
            "robot": self.robot,
            "q": list(self.q),
            "kappa": self.kappa,
            "lowest": self.lowest.to_dict(),
            "highest": self.highest.to_dict(),
        }


def _ranked(names, values) -> tuple[tuple[str, float], ...]:
    pairs = [(name, float(value)) for name, value in zip(names, values, strict=True)]
    return tuple(sorted(pairs, key=lambda pair: -pair[1]))


def gim_modes(robot: Robot, q: npt.ArrayLike | None = None, *, metric: str = "kappa") -> GimModes:
    """Explain κ(M(q)) by the modes of λmin and λmax (dense path; Pinocchio's Data is built).

    Args:
        robot: The robot.
        q: Configuration, length nq (default: neutral).
        metric: ``kappa`` (modes of M) or ``kappa_equilibrated``: modes of S = D^-1/2 M D^-1/2,
            eigenvalue μ of S; joints ranked by u_i² of S's unit eigenvector u (the same in any
            units), bodies by the energy of the motion v = D^-1/2 u (vᵀ M v = μ).
    """
    if metric not in ("kappa", "kappa_equilibrated"):
        raise InputError("metric", "kappa or kappa_equilibrated", metric)
    model = robot.model
    q = pin.neutral(model) if q is None else as_configuration(robot, q)
    data = robot.new_data()
    M = check_robot_gim(robot, np.array(pin.crba(model, data, q)))
    scale = np.ones(M.shape[0]) if metric == "kappa" else 1.0 / np.sqrt(np.diag(M))
    w, vectors = np.linalg.eigh(M * np.outer(scale, scale))
    split = body_split(robot, q, data=data)
    joints = dof_joint_ranges(robot)
    bodies = body_names(robot)
    modes = []
    for index in (0, w.size - 1):
        u = vectors[:, index]
        v = scale * u  # the motion, in the robot's coordinates
        participation = [float(np.sum(u[start : start + nv] ** 2)) for _, start, nv in joints]
        energy = body_energies(split, v)
        armature = float(v @ (split.armature * v))
        modes.append(
            Mode(
                eigenvalue=float(w[index]),
                vector=tuple(float(x) for x in u),
                joints=_ranked([name for name, _, _ in joints], participation),
                bodies=_ranked(bodies, energy / energy.sum()),
                armature_share=armature / float(w[index]),
            )
        )
    return GimModes(
        robot=robot.name,
        q=tuple(float(x) for x in q),
        kappa=extreme_ratio(w),
        lowest=modes[0],
        highest=modes[1],
    )
