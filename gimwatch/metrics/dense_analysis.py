"""One-shot conditioning analysis of a robot's GIM at given configurations."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt

from gimwatch.errors import ConditioningError
from gimwatch.metrics.conditioning import (
    check_gim,
    diagonal_ratio,
    eigenvalues,
    ldlt_pivots,
    udut_pivots,
    warn_if_ill_conditioned,
)
from gimwatch.model.inertia import gim
from gimwatch.model.robots import Robot, as_configuration

__all__ = ["GimAnalysis", "analyze_configuration", "check_massless", "check_robot_gim"]


@dataclass(frozen=True)
class GimAnalysis:
    """Conditioning of M(q) at one configuration.

    Attributes:
        robot: Robot name.
        method: ``"crba"`` (dense M from Pinocchio, symmetric eigensolver) or
            ``"denoc-linear"`` (the O(n) path of :mod:`gimwatch.metrics.linear_analysis`: κ by
            Lanczos,
            ``eigenvalues`` only (λmin, λmax), no forward pivots).
        nv: Size of the GIM.
        q: The configuration (length nq).
        kappa: κ₂ = λmax/λmin (None when not asked for).
        diagonal_ratio: δ = max M_ii / min M_ii.
        pivot_ratio_forward: max/min LDLᵀ pivot (elimination from the root).
        pivot_ratio_backward: max/min UDUᵀ pivot (elimination from the tips).
        lambda_min: Smallest eigenvalue.
        lambda_max: Largest eigenvalue.
        eigenvalues: All eigenvalues, ascending.
        diagonal: diag M, in Pinocchio's coordinate order.
        max_diagonal_dof: Name of the coordinate holding the largest diagonal entry.
        min_diagonal_dof: Name of the coordinate holding the smallest diagonal entry.
    """

    robot: str
    nv: int
    q: tuple[float, ...]
    kappa: float | None
    diagonal_ratio: float
    pivot_ratio_forward: float | None
    pivot_ratio_backward: float | None
    lambda_min: float | None
    lambda_max: float | None
    eigenvalues: tuple[float, ...]
    diagonal: tuple[float, ...]
    max_diagonal_dof: str
    min_diagonal_dof: str
    method: str = "crba"

    def to_dict(self) -> dict:
        """A JSON-ready dict (lists for the vectors)."""
        record = asdict(self)
        for key in ("q", "eigenvalues", "diagonal"):
            record[key] = list(record[key])
        return record


def check_massless(
    diagonal: np.ndarray, dof_names: Sequence[str], *, name: str, source: str
) -> None:
    """Raise if a coordinate moves no mass (M_kk <= 0: M singular), naming the coordinates.

    Raises:
        ConditioningError: ``source: M(q) of name is singular: ... (coordinates); remedy``.
    """
    massless = [dof_names[k] for k in np.flatnonzero(~(np.asarray(diagonal) > 0))]
    if massless:
        raise ConditioningError(
            f"{source}: M(q) of {name} is singular: "
            f"{len(massless)} coordinate(s) move no mass "
            f"({', '.join(massless[:4])}{', ...' if len(massless) > 4 else ''}); "
            "give the links they move an <inertial>"
        )


def check_robot_gim(robot: Robot, M: np.ndarray) -> np.ndarray:
    """Check M(q) of ``robot`` like :func:`~gimwatch.metrics.conditioning.check_gim`, naming joints.

    Raises:
        ConditioningError: A coordinate moves no mass (M singular), naming the URDF and the
            coordinates; or M is not a valid GIM.
    """
    check_massless(np.diag(M), robot.dof_names, name=robot.name, source=robot.source)
    return check_gim(M)


def analyze_configuration(robot: Robot, q: npt.ArrayLike, *, data=None) -> GimAnalysis:
    """Compute κ, δ, both pivot ratios and the spectrum of M(q)."""
    q = as_configuration(robot, q)
    M = check_robot_gim(robot, gim(robot, q, data=data))
    values = eigenvalues(M)
    diag = np.diag(M)
    forward, backward = ldlt_pivots(M), udut_pivots(M)
    kappa = float(values[-1] / values[0])
    warn_if_ill_conditioned(kappa, where=robot.name)
    return GimAnalysis(
        robot=robot.name,
        nv=robot.nv,
        q=tuple(float(x) for x in q),
        kappa=kappa,
        diagonal_ratio=diagonal_ratio(diag),
        pivot_ratio_forward=float(forward.max() / forward.min()),
        pivot_ratio_backward=float(backward.max() / backward.min()),
        lambda_min=float(values[0]),
        lambda_max=float(values[-1]),
        eigenvalues=tuple(float(x) for x in values),
        diagonal=tuple(float(x) for x in diag),
        max_diagonal_dof=robot.dof_names[int(np.argmax(diag))],
        min_diagonal_dof=robot.dof_names[int(np.argmin(diag))],
    )
