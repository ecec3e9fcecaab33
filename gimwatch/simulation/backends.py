"""Forward-dynamics backends: a = FD(q, v, τ) with gravity set once, in a registry.

* ``aba`` — Pinocchio's articulated-body algorithm, O(n) (Featherstone's ABA).
* ``crba-cholesky`` — ``M(q) a = τ - b(q, v)`` with M from Pinocchio's CRBA, b from its
  RNEA (``nonLinearEffects``) and a dense Cholesky solve (SciPy ``cho_solve``), O(n³).
* ``denoc`` — gimwatch's own DeNOC recursion (``gimwatch.denoc``, no Pinocchio), imported
  lazily so that this module works without it.

Each backend owns a copy of the Pinocchio model whose ``gravity`` is the scene's vector,
or zero when the scene declares no gravity: the recursions then add nothing for it.

A backend is also where the watch and the energy get M(q), diag M(q) and the energy from,
so that a long chain on ``denoc`` never builds a Pinocchio Data (its memory grows as nv³):
above `DATA_NV_LIMIT` coordinates, [`make_backend`][gimwatch.simulation.backends.make_backend]
switches to ``denoc`` and says so with a [`BackendWarning`][gimwatch.errors.BackendWarning].
"""

from __future__ import annotations

import warnings
from typing import ClassVar

import numpy as np
import pinocchio as pin
import scipy.linalg

from gimwatch.errors import BackendWarning
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.mass_matrix_source import GUARANTEED, Configuration, MassMatrixSource
from gimwatch.model.robots import DATA_NV_LIMIT, Robot

__all__ = ["BACKENDS", "Backend", "make_backend", "model_with_gravity"]


def model_with_gravity(robot: Robot, gravity: np.ndarray | None) -> pin.Model:
    """A copy of the robot's model whose gravity is ``gravity`` (m/s²), or zero if None."""
    model = pin.Model(robot.model)
    linear = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)
    model.gravity = pin.Motion(linear, np.zeros(3))
    return model


class Backend(MassMatrixSource):
    """Forward dynamics of one robot under one gravity vector; a source of its M(q) too.

    A backend is the [`MassMatrixSource`][gimwatch.model.mass_matrix_source.MassMatrixSource] a
    simulation hands its watch: q comes from the integrator (not checked again) and M is
    positive definite by construction (the robot's masses were checked when it was loaded).
    """

    name: ClassVar[str]
    robot: Robot
    check_q = False
    definiteness = GUARANTEED

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        self.robot = robot
        self.nv, self.dof_names = robot.nv, robot.dof_names
        self.gravity = np.zeros(3) if gravity is None else np.asarray(gravity, dtype=float)

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """Joint accelerations a (length nv) for the generalized force τ."""
        raise NotImplementedError

    def _pinocchio(self) -> tuple[pin.Model, pin.Data]:
        """The model with the scene's gravity and a Data, made on first use."""
        if not hasattr(self, "model"):
            self.model = model_with_gravity(self.robot, self.gravity)
        if not hasattr(self, "data"):
            self.data = self.robot.new_data()
        return self.model, self.data

    def gim(self, q: Configuration) -> np.ndarray:
        """M(q), from Pinocchio's CRBA."""
        return gim(self.robot, q, data=self._pinocchio()[1])

    def gim_diagonal(self, q: Configuration) -> np.ndarray:
        """Diag M(q) in O(n), from Pinocchio's composite inertias."""
        return gim_diagonal(self.robot, q, data=self._pinocchio()[1])

    def energy(self, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
        """(kinetic, gravity potential) energy in J, from Pinocchio."""
        model, data = self._pinocchio()
        kinetic = pin.computeKineticEnergy(model, data, q, v)
        return float(kinetic), float(pin.computePotentialEnergy(model, data, q))


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
    """gimwatch's DeNOC forward dynamics (imported when the backend is built).

    With a fixed base the recursions are the compiled O(n) ones, and M's diagonal and the
    energy come from them too, so no Pinocchio Data is ever built.
    """

    name = "denoc"

    def __init__(self, robot: Robot, gravity: np.ndarray | None) -> None:
        super().__init__(robot, gravity)
        from gimwatch.metrics.denoc_robot import denoc_model

        self.denoc = denoc_model(robot)
        self._g = tuple(float(x) for x in self.gravity)
        self.lean = self.denoc.lean()  # one compiled call per evaluation, buffers kept

    def forward_dynamics(self, q, v, tau):
        return self.lean.forward_dynamics(
            np.asarray(q, dtype=float),
            np.asarray(v, dtype=float),
            np.asarray(tau, dtype=float),
            self.gravity,
        )

    def gim(self, q):
        return self.denoc.gim(q)

    def lean_model(self):
        """The compiled model of the forward dynamics: the watch's diag M and δ too."""
        return self.lean

    def gim_diagonal(self, q):
        return self.lean.gim_diagonal(np.asarray(q, dtype=float))

    def energy(self, q, v):
        return self.denoc.energy(q, v, gravity=self._g)  # O(n), any tree DeNOC reads


#: The registry: scene backend name -> class.
BACKENDS: dict[str, type[Backend]] = {
    cls.name: cls for cls in (AbaBackend, CrbaCholeskyBackend, DenocBackend)
}


def make_backend(name: str, robot: Robot, gravity: np.ndarray | None) -> Backend:
    """Build the backend registered as ``name`` (``denoc`` instead above DATA_NV_LIMIT)."""
    if name != DenocBackend.name and robot.nv > DATA_NV_LIMIT:
        warnings.warn(
            f"{robot.name} has nv = {robot.nv} > {DATA_NV_LIMIT}: using the O(n) denoc backend "
            f"instead of {name} (Pinocchio's Data would need GBs)",
            BackendWarning,
            stacklevel=2,
        )
        name = DenocBackend.name
    return BACKENDS[name](robot, gravity)
