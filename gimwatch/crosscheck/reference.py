"""The cross-check's reference: Pinocchio's CRBA, RNEA, ABA and UDUᵀ pivots at one state.

M(q) is taken from ``pinocchio.crba`` on the rigid model (armature zeroed: DeNOC models rigid
bodies), checked finite, and labelled once per sample: its eigenvalues, whether it is
numerically rank-deficient (λmin <= nv·ε·λmax) and its κ₂. The relative-error helpers every
comparison uses live here too.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from gimwatch.errors import InputError, URDFError
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.model.robots import Robot

__all__ = [
    "EPS",
    "PinocchioReference",
    "ReferenceSample",
    "check_tolerance",
    "pivot_error",
    "relative_error",
]

#: Machine epsilon of float64, the unit of the round-off floor κ·ε.
EPS = float(np.finfo(float).eps)


def check_tolerance(tolerance: float, name: str = "tolerance") -> float:
    """A relative tolerance must be a number in (0, 1): inf or 1 would pass every error."""
    if isinstance(tolerance, bool) or not isinstance(tolerance, (int, float, np.floating)):
        raise InputError(name, "a number > 0 and < 1", tolerance)
    if not 0 < tolerance < 1:
        raise InputError(name, "a number > 0 and < 1", tolerance)
    return float(tolerance)


def relative_error(x: np.ndarray, reference: np.ndarray) -> float:
    """‖x − reference‖ / ‖reference‖ (Frobenius or 2-norm); the absolute error if ‖ref‖ = 0."""
    scale = float(np.linalg.norm(reference))
    return float(np.linalg.norm(x - reference)) / (scale if scale > 0 else 1.0)


def pivot_error(pivots: np.ndarray, reference: np.ndarray) -> tuple[float, bool]:
    """Relative error of the pivots, and whether M is singular (a pivot ~0 or not finite).

    UDUᵀ eliminates from the last coordinate; after a zero pivot the rest are undefined
    (NaN, inf or round-off noise), so then only those eliminated before it are compared, and
    both factorisations must meet the zero at the same coordinate (else the error is inf).
    """
    finite = np.concatenate([pivots[np.isfinite(pivots)], reference[np.isfinite(reference)]])
    floor = 100 * pivots.size * EPS * (np.abs(finite).max() if finite.size else 0.0)
    bad = [np.flatnonzero(~(np.isfinite(x) & (x > floor))) for x in (pivots, reference)]
    if not bad[0].size and not bad[1].size:
        return relative_error(pivots, reference), False
    if not (bad[0].size and bad[1].size) or bad[0][-1] != bad[1][-1]:
        return float("inf"), True
    start = bad[0][-1] + 1
    return relative_error(pivots[start:], reference[start:]), True


@dataclass(frozen=True)
class ReferenceSample:
    """Pinocchio's M(q) at one configuration, labelled.

    Attributes:
        M: The full symmetric mass matrix of the rigid model (kg·m², kg·m, kg).
        eigenvalues: Its eigenvalues, ascending.
        rank_deficient: λmin <= nv·ε·λmax: q̈ is undefined.
        kappa: κ₂(M) = λmax / λmin, inf when rank-deficient.
    """

    M: np.ndarray
    eigenvalues: np.ndarray
    rank_deficient: bool
    kappa: float


class PinocchioReference:
    """Pinocchio's dynamics of ``robot``, rigid (armature zeroed) and as loaded.

    Args:
        robot: The robot (fixed or floating base, as loaded).
    """

    def __init__(self, robot: Robot) -> None:
        self.robot = robot
        self.full_model, self.full_data = robot.model, robot.new_data()
        self.model, self.data = self.full_model, self.full_data
        if np.any(np.asarray(self.full_model.armature)):  # DeNOC's input has no armature
            self.model = self.full_model.copy()
            self.model.armature = np.zeros(self.model.nv)
            self.data = self.model.createData()

    def sample(self, q: np.ndarray) -> ReferenceSample:
        """M(q) by ``crba`` (rigid), its eigenvalues, rank deficiency and κ₂.

        Raises:
            URDFError: M(q) is not finite (an overflow in the model), naming the file.
        """
        M = self._symmetric(pin.crba(self.model, self.data, q))
        if not np.all(np.isfinite(M)):
            raise URDFError(
                self.robot.source,
                "Pinocchio's mass matrix M(q) is not finite (inf or NaN): a mass, inertia or "
                "length in the model is too large",
            )
        eigenvalues = np.linalg.eigvalsh(M)
        rank_deficient = bool(eigenvalues[0] <= self.robot.nv * EPS * eigenvalues[-1])
        kappa = np.inf if rank_deficient else extreme_ratio(eigenvalues)
        return ReferenceSample(M, eigenvalues, rank_deficient, float(kappa))

    def mass_matrix_as_loaded(self, q: np.ndarray, sample: ReferenceSample) -> np.ndarray:
        """M(q) with the robot's armature (``sample.M`` when it has none)."""
        if self.model is self.full_model:
            return sample.M
        return self._symmetric(pin.crba(self.full_model, self.full_data, q))

    def inverse_dynamics(self, q: np.ndarray, v: np.ndarray, a: np.ndarray) -> np.ndarray:
        """τ by ``rnea`` (N·m, N)."""
        return np.array(pin.rnea(self.model, self.data, q, v, a))

    def forward_dynamics(self, q: np.ndarray, v: np.ndarray, tau: np.ndarray) -> np.ndarray:
        """q̈ by ``aba`` (rad/s², m/s²)."""
        return np.array(pin.aba(self.model, self.data, q, v, tau))

    def pivots(self, q: np.ndarray) -> np.ndarray:
        """The D of ``cholesky.decompose`` (M = U D Uᵀ, eliminated from the last coordinate)."""
        pin.crba(self.model, self.data, q)
        pin.cholesky.decompose(self.model, self.data)
        return np.array(self.data.D)

    def singular_joints(self, M: np.ndarray) -> str:
        """The joints of the null direction of a rank-deficient M (largest components)."""
        _, vectors = np.linalg.eigh(M)
        null = np.abs(vectors[:, 0])
        dofs = [self.robot.dof_names[k] for k in np.flatnonzero(null >= 0.1 * null.max())]
        return ", ".join(dofs[:6]) + (", ..." if len(dofs) > 6 else "")

    @staticmethod
    def _symmetric(crba: np.ndarray) -> np.ndarray:
        """The full M from the upper triangle ``crba`` fills."""
        upper = np.triu(crba)
        return upper + np.triu(upper, 1).T
