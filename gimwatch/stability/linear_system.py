"""The robot linearised where its servos hold it: M ẍ + C ẋ + K x = 0 about q_held.

At the held configuration (v = 0) the generalized force f(q, v) = servo forces + joint springs
and dampers − g(q) has K = −∂f/∂q and C = −∂f/∂v:

* K = diag(servo and joint-spring stiffness) + ∂g/∂q, gravity's stiffness from Pinocchio's
  ``computeGeneralizedGravityDerivatives`` (left out with ``gravity=False``);
* C = diag(actuator damping) + diag(joint damping), kept apart because integrators treat them
  differently (MuJoCo's ``Euler`` takes joint damping implicitly, actuator damping explicitly);
* M = M(q_held), armature included (Pinocchio's CRBA, as ``mj_fullM``).

Coriolis forces are quadratic in v, so their derivative vanishes at rest: the linear model
is the same for MuJoCo's ``implicit`` and ``implicitfast``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gimwatch.errors import ConditioningError
from gimwatch.stability.servos import Servos

__all__ = ["LinearSystem", "linearise"]


@dataclass(frozen=True)
class LinearSystem:
    """M ẍ + (C_explicit + D_joint) ẋ + K x = 0 (SI units, nv × nv each).

    Attributes:
        mass: M(q_held), kg·m² / kg.
        stiffness: K, N·m/rad or N/m (not symmetric in general: gravity's part is not).
        explicit_damping: Actuator damping (diagonal matrix), N·m·s/rad.
        joint_damping: Joint damping (diagonal matrix), N·m·s/rad.
    """

    mass: np.ndarray
    stiffness: np.ndarray
    explicit_damping: np.ndarray
    joint_damping: np.ndarray

    @property
    def damping(self) -> np.ndarray:
        """C, all the damping."""
        return self.explicit_damping + self.joint_damping

    @property
    def n(self) -> int:
        """Number of coordinates."""
        return self.mass.shape[0]

    def state_matrix(self) -> np.ndarray:
        """A of ẋ = A x on x = (q, v), shape 2n × 2n."""
        n = self.n
        solve = np.linalg.solve(self.mass, np.hstack([self.stiffness, self.damping]))
        return np.block([[np.zeros((n, n)), np.eye(n)], [-solve[:, :n], -solve[:, n:]]])

    def with_mass(self, added: np.ndarray) -> LinearSystem:
        """The same system with ``diag(added)`` added to M (armature)."""
        return LinearSystem(
            self.mass + np.diag(added), self.stiffness, self.explicit_damping, self.joint_damping
        )


def _check_massive(model: pin.Model, mass: np.ndarray, source: str) -> None:
    """Refuse an M(q) that is not positive definite, naming the coordinates moving no mass.

    A coordinate that moves no mass has no time scale (its mode's frequency is infinite).
    """
    names = [n for j, n in zip(model.joints[1:], model.names[1:], strict=True) for _ in range(j.nv)]
    massless = [names[k] for k in np.flatnonzero(~(mass.diagonal() > 0))]
    if massless:
        raise ConditioningError(
            f"{source}: M(q) of {model.name} is singular: {len(massless)} coordinate(s) move "
            f"no mass ({', '.join(massless)}); give the links they move an <inertial>"
        )
    if not np.all(np.isfinite(mass)):
        raise ConditioningError(f"{source}: M(q) of {model.name} is not finite")
    try:  # M(q) from CRBA is symmetric; NumPy's Cholesky (potrf) fails unless it is SPD
        np.linalg.cholesky(mass)
    except np.linalg.LinAlgError as exc:
        raise ConditioningError(
            f"{source}: M(q) of {model.name} is not positive definite ({exc})"
        ) from exc


def linearise(
    model: pin.Model,
    servos: Servos,
    q: np.ndarray,
    *,
    gravity: bool = True,
    data=None,
    source: str = "",
) -> LinearSystem:
    """The linear system of a robot's Pinocchio ``model`` held at ``q`` by ``servos``.

    Args:
        model: The robot's Pinocchio model (its ``gravity`` is the one linearised).
        servos: Its servos (`gimwatch.stability.servos`).
        q: The held configuration (Pinocchio's q; MuJoCo's qpos for MJCF).
        gravity: Include gravity's stiffness ∂g/∂q.
        data: A Pinocchio Data of ``model`` to reuse.
        source: The robot's file, named by an error (the model's name when empty).

    Raises:
        ConditioningError: M(q) is not positive definite (a coordinate moves no mass).
    """
    data = model.createData() if data is None else data
    mass = np.array(pin.crba(model, data, q))
    mass = np.triu(mass) + np.triu(mass, 1).T
    _check_massive(model, mass, source or model.name)
    stiffness = np.diag(servos.stiffness)
    if gravity:
        stiffness = stiffness + np.array(pin.computeGeneralizedGravityDerivatives(model, data, q))
    return LinearSystem(
        mass=mass,
        stiffness=stiffness,
        explicit_damping=np.diag(servos.explicit_damping),
        joint_damping=np.diag(servos.joint_damping),
    )
