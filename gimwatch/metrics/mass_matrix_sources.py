"""M(q) from Pinocchio's CRBA and from DeNOC: three `MassMatrixSource` implementations.

* [`PinocchioSource`][gimwatch.metrics.mass_matrix_sources.PinocchioSource] — a gimwatch robot
  and its Pinocchio Data: M by CRBA, diag M without M (composite inertias; CRBA's C++ below
  `CRBA_DIAGONAL_MAX_NV`);
* [`DenocDiagonal`][gimwatch.metrics.mass_matrix_sources.DenocDiagonal] — another source whose
  diag M and δ come from DeNOC's compiled lean model (one call, buffers kept), M from the
  other source when a metric asks for it;
* [`DenocLinear`][gimwatch.metrics.mass_matrix_sources.DenocLinear] — DeNOC's linear-time
  state (O(n) M·x, M⁻¹·y, diagonal and UDUᵀ pivots): M is never formed.

[`diagonal_source`][gimwatch.metrics.mass_matrix_sources.diagonal_source] picks what a
consumer that never forms M samples from a robot's source.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from gimwatch.errors import ConditioningError, GimwatchError
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.mass_matrix_source import (
    CHECK_ONCE,
    GUARANTEED,
    Configuration,
    LinearState,
    MassMatrixSource,
)
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import DATA_NV_LIMIT, Robot

__all__ = [
    "CRBA_DIAGONAL_MAX_NV",
    "DenocDiagonal",
    "DenocLinear",
    "PinocchioSource",
    "diagonal_source",
]

#: Up to this nv, diag M of a robot reads CRBA's diagonal (C++, O(n²)) rather than the O(n)
#: centroidal map, whose Python around Pinocchio costs more.
CRBA_DIAGONAL_MAX_NV = 40


class PinocchioSource(MassMatrixSource):
    """M of a gimwatch robot from Pinocchio's CRBA, with a Data of its own.

    Args:
        robot: The robot.
        data: A Pinocchio Data to use; None: one made when a computation needs it (refused
            above `DATA_NV_LIMIT`, where diag M still comes without one).
    """

    robot: Robot

    def __init__(self, robot: Robot, data: pin.Data | None = None) -> None:
        self.robot = robot
        self.nv, self.dof_names = robot.nv, robot.dof_names
        self.data = data
        # a robot too long for Data is never checked by forming M (a metric needing M says so)
        self.definiteness = CHECK_ONCE if robot.nv <= DATA_NV_LIMIT else GUARANTEED

    def pinocchio_data(self) -> pin.Data | None:
        """The Data this source holds (None until a computation needs one)."""
        return self.data

    def _data(self) -> pin.Data:
        if self.data is None:  # refused above DATA_NV_LIMIT, naming the O(n) path
            self.data = self.robot.new_data()
        return self.data

    def gim(self, q: Configuration) -> np.ndarray:
        """M(q), checked q, from CRBA (symmetric copy)."""
        return gim(self.robot, q, data=self._data())

    def gim_into(self, q: Configuration, out: np.ndarray) -> np.ndarray:
        """CRBA's M in the Data (upper triangle filled): q is already checked by the watch."""
        data = self.data if self.data is not None else self._data()
        return pin.crba(self.robot.model, data, q)

    def gim_diagonal(self, q: Configuration) -> np.ndarray:
        """Diag M(q): CRBA's diagonal for small robots, else O(n) composite inertias."""
        if self.nv <= CRBA_DIAGONAL_MAX_NV:  # C++ CRBA beats the O(n) map in Python here
            q = as_configuration(self.robot, q)
            return pin.crba(self.robot.model, self._data(), q).diagonal().copy()
        return gim_diagonal(self.robot, q, data=self.data)


class DenocDiagonal(MassMatrixSource):
    """Diag M and δ from DeNOC's compiled lean model; M (when asked) from another source.

    Args:
        inner: The source of M (Pinocchio's CRBA, a simulation backend).
        lean: DeNOC's [`LeanModel`][gimwatch.denoc.LeanModel] of the same robot, in
            Pinocchio's coordinate order.
    """

    definiteness = GUARANTEED

    def __init__(self, inner: MassMatrixSource, lean: Any) -> None:
        self.inner, self.lean = inner, lean
        self.nv, self.dof_names, self.robot = inner.nv, inner.dof_names, inner.robot
        self.check_q = inner.check_q  # type: ignore[misc]  # the inner source's rule
        # bound once, so that a sample makes one call into the compiled model, not two
        self.gim_diagonal = lean.gim_diagonal  # type: ignore[method-assign]
        self.diagonal_ratio = lean.diagonal_ratio  # type: ignore[method-assign]

    def gim(self, q: Configuration) -> np.ndarray:
        """M(q) from the inner source."""
        return self.inner.gim(q)

    def gim_into(self, q: Configuration, out: np.ndarray) -> np.ndarray:
        """M(q) from the inner source, into ``out`` when it can."""
        return self.inner.gim_into(q, out)

    def lean_model(self) -> Any:
        """The lean model serving diag M and δ."""
        return self.lean

    def pinocchio_data(self) -> Any:
        """The inner source's Pinocchio Data."""
        return self.inner.pinocchio_data()


class DenocLinear(MassMatrixSource):
    """DeNOC's linear-time state of M: O(n) products, diagonal and pivots; M never formed.

    Args:
        model: The [`DenocModel`][gimwatch.denoc.DenocModel].
    """

    definiteness = GUARANTEED

    def __init__(self, model: Any) -> None:
        self.model = model
        self.nv, self.dof_names = model.nv, tuple(model.dof_names)
        self._q: Configuration = None
        self._state: LinearState | None = None

    def gim(self, q: Configuration) -> np.ndarray:
        """Refused: the O(n) path never forms M."""
        raise ConditioningError("this metric needs M itself, which the O(n) path never forms")

    def linear_state(self, q: Configuration) -> LinearState:
        """The model's state at q, kept while q is the same configuration."""
        if self._state is None or self._q is None or not np.array_equal(q, self._q):
            self._state = self.model.state(q)
            self._q = np.array(q, dtype=float)
        return self._state

    def gim_diagonal(self, q: Configuration) -> np.ndarray:
        """Diag M(q) from the linear state, in public order."""
        return self.to_public(self.linear_state(q).diagonal())

    def to_public(self, x: np.ndarray) -> np.ndarray:
        """The model's body order mapped to public (``dof_names``) order."""
        return self.model.to_public(x)


def diagonal_source(source: MassMatrixSource) -> MassMatrixSource:
    """The source a consumer that never forms M samples: DeNOC's diagonal when it reads the robot.

    A source that has a robot gets DeNOC's lean model (the source's own, else one built from
    the robot's URDF or chain) for diag M and δ; a robot DeNOC cannot read, or a source
    without a robot, is returned as it is.
    """
    robot = source.robot
    if robot is None:
        return source
    lean = source.lean_model()
    if lean is None and (robot.urdf_xml or robot.chain is not None):
        from gimwatch.metrics.denoc_robot import denoc_model

        try:
            lean = denoc_model(robot).lean()
        except GimwatchError:  # a joint type DeNOC does not read
            lean = None
    return source if lean is None else DenocDiagonal(source, lean)
