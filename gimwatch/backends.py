"""Forward-dynamics backends: a = FD(q, v, τ) with gravity set once, in a registry.

* ``aba`` — Pinocchio's articulated-body algorithm, O(n) (Featherstone's ABA).
* ``crba-cholesky`` — ``M(q) a = τ - b(q, v)`` with M from Pinocchio's CRBA, b from its
  RNEA (``nonLinearEffects``) and a dense Cholesky solve (SciPy ``cho_solve``), O(n³).
* ``denoc`` — gimwatch's own DeNOC recursion (``gimwatch.denoc``, no Pinocchio), imported
  lazily so that this module works without it.

Each backend owns a copy of the Pinocchio model whose ``gravity`` is the scene's vector,
or zero when the scene declares no gravity: the recursions then add nothing for it.
"""

from __future__ import annotations

from typing import ClassVar

import numpy as np
import pinocchio as pin
import scipy.linalg

from gimwatch.robots import Robot

__all__ = ["BACKENDS", "Backend", "make_backend", "model_with_gravity"]


def model_with_gravity(robot: Robot, gravity: np.ndarray | None) -> pin.Model:
    """A copy of the robot's model whose gravity is ``gravity`` (m/s²), or zero if None."""
    model = pin.Model(robot.model)
    linear = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
    model.gravity = pin.Motion(linear, np.zeros(3))
    return model


class Backend:
    """Forward dynamics of one robot under one gravity vector."""

    name: ClassVar[str]

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        self.robot = robot
        self.gravity = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations a (length nv) for the generalized force τ."""
        raise NotImplementedError


class AbaBackend(Backend):
    """Pinocchio ``aba``: O(n), no mass matrix formed."""

    name = "aba"

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        super().__init__(robot, gravity)
        self.model = model_with_gravity(robot, gravity)
        self.data = robot.new_data()

    def forward_dynamics(self, q, v, tau):
        return pin.aba(self.model, self.data, q, v, tau)


class CrbaCholeskyBackend(Backend):
    """``a = M⁻¹ (τ - b)``: CRBA mass matrix, RNEA bias, dense Cholesky solve."""

    name = "crba-cholesky"

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        super().__init__(robot, gravity)
        self.model = model_with_gravity(robot, gravity)
        self.data = robot.new_data()

    def forward_dynamics(self, q, v, tau):
        M = pin.crba(self.model, self.data, q)
        bias = pin.nonLinearEffects(self.model, self.data, q, v)
        factor = scipy.linalg.cho_factor(M, lower=False, check_finite=False)
        return scipy.linalg.cho_solve(factor, tau - bias, check_finite=False)


class DenocBackend(Backend):
    """gimwatch's DeNOC forward dynamics (imported when the backend is built)."""

    name = "denoc"

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        super().__init__(robot, gravity)
        from gimwatch.denoc import DenocModel

        self.denoc = DenocModel.from_urdf(
            robot.urdf_xml, floating=robot.floating, joint_order=robot.joint_names
        )
        self._g = tuple(float(x) for x in self.gravity)

    def forward_dynamics(self, q, v, tau):
        return np.asarray(self.denoc.forward_dynamics(q, v, tau, gravity=self._g), dtype=float)


#: The registry: scene backend name -> class.
BACKENDS: dict[str, type[Backend]] = {
    cls.name: cls for cls in (AbaBackend, CrbaCholeskyBackend, DenocBackend)
}


def make_backend(name: str, robot: Robot, gravity: np.ndarray | None) -> Backend:
    """Build the backend registered as ``name``."""
    return BACKENDS[name](robot, gravity)
