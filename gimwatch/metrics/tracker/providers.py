"""Where the κ tracker and the watch's δ get their O(n) operators from.

* [`lean_model`][gimwatch.metrics.tracker.providers.lean_model] — DeNOC's compiled
  [`LeanModel`][gimwatch.denoc.LeanModel] of a robot (the backend's when it has one, else built once
  from the chain spec or the URDF), or None when DeNOC cannot read the robot;
* [`gim_products`][gimwatch.metrics.tracker.providers.gim_products] — that model, or else
  [`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts];
* [`PinocchioProducts`][gimwatch.metrics.tracker.providers.PinocchioProducts] — ``M(q) x = RNEA(q,
  0, x)`` and ``M(q)⁻¹ y = ABA(q, 0, y)`` with gravity off, behind the three methods
  [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] calls (``configure(q)``,
  ``gim_product(x)``, ``gim_solve(y)``): for robots DeNOC does not read, or to check one
  implementation against the other. DeNOC's model is the cheaper provider: its products reuse the
  configuration's kinematics and factor, Pinocchio's recompute them every call.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

from gimwatch.errors import GimwatchError
from gimwatch.model.mass_matrix_source import MassMatrixSource
from gimwatch.model.robots import Robot

__all__ = ["PinocchioProducts", "gim_products", "lean_model"]


def lean_model(robot: Robot, dynamics: MassMatrixSource | None = None):
    """DeNOC's compiled model of ``robot`` in Pinocchio's coordinate order, or None.

    Args:
        robot: The robot.
        dynamics: The source of M (a simulation backend); its declared lean model is reused.
    """
    lean = None if dynamics is None else dynamics.lean_model()
    if lean is not None:
        return lean
    from gimwatch.metrics.denoc_robot import denoc_model

    try:
        return denoc_model(robot).lean()
    except GimwatchError:  # a joint type DeNOC does not read
        return None


def gim_products(robot: Robot, dynamics=None, data: pin.Data | None = None):
    """The cheapest provider of M·x and M⁻¹·y for ``robot``: DeNOC's, else Pinocchio's."""
    lean = lean_model(robot, dynamics)
    return lean if lean is not None else PinocchioProducts(robot, data)


class PinocchioProducts:
    """RNEA / ABA at zero velocity and gravity as M·x and M⁻¹·y.

    Args:
        robot: The robot.
        data: A Pinocchio Data to reuse (one is made when omitted).
    """

    def __init__(self, robot: Robot, data: pin.Data | None = None) -> None:
        self.model = pin.Model(robot.model)
        self.model.gravity = pin.Motion.Zero()
        self.data = robot.new_data() if data is None else data
        self.nv = robot.nv
        self._zero = np.zeros(robot.nv)
        self._q = np.zeros(robot.nq)
        self._diagonal: np.ndarray | None = None

    def configure(self, q: np.ndarray) -> None:
        """Set the configuration of the products."""
        self._q = np.asarray(q, dtype=float)
        self._diagonal = None  # CRBA's M at q, computed when a certificate asks for it

    def _crba(self) -> np.ndarray:
        """CRBA's M at the configured q into ``data.M`` (upper triangle); its diagonal."""
        if self._diagonal is None:
            pin.crba(self.model, self.data, self._q)
            self._diagonal = np.diag(self.data.M).copy()
        return self._diagonal

    def shifted_inertia(self, shift: float, weights: np.ndarray | None = None) -> tuple[int, int]:
        """(positive, negative) pivots of M(q) − shift·W (armature included), W = diag(weights).

        Pinocchio's sparse LDLᵀ of CRBA's M (``pinocchio.cholesky.decompose``, the tree's
        sparsity) with the shift on the diagonal: a congruence, so by Sylvester's law of inertia
        the pivot signs count the eigenvalues of M above and below ``shift`` (W = 1, the
        default), or those of W^-1/2 M W^-1/2 for a positive diagonal W.
        """
        diagonal = self._crba()
        M = self.data.M  # a view of Pinocchio's buffer
        M[np.diag_indices(self.nv)] = diagonal - (shift if weights is None else shift * weights)
        pin.cholesky.decompose(self.model, self.data)
        M[np.diag_indices(self.nv)] = diagonal
        pivots = np.asarray(self.data.D)
        return int(np.count_nonzero(pivots > 0)), int(np.count_nonzero(pivots < 0))

    def gim_matrix(self) -> np.ndarray:
        """M(q) at the configured q (CRBA, symmetric), for a dense recovery."""
        self._crba()
        upper = np.triu(self.data.M)
        return upper + np.triu(upper, 1).T

    def gim_product(self, x: np.ndarray) -> np.ndarray:
        """M(q) x."""
        return pin.rnea(self.model, self.data, self._q, self._zero, x)

    def gim_solve(self, y: np.ndarray) -> np.ndarray:
        """M(q)⁻¹ y."""
        return pin.aba(self.model, self.data, self._q, self._zero, y)
