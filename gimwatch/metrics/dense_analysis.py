"""One-shot conditioning analysis of a robot's GIM at given configurations."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt

from gimwatch.errors import ConditioningError
from gimwatch.metrics.conditioning import check_gim, warn_if_ill_conditioned
from gimwatch.metrics.mass_matrix_sources import PinocchioSource
from gimwatch.metrics.registry import GimState, evaluate
from gimwatch.model.inertia import gim
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = [
    "ANALYSIS_METRICS",
    "GimAnalysis",
    "analysis_record",
    "analyze_configuration",
    "check_massless",
    "check_robot_gim",
]


@dataclass(frozen=True)
class GimAnalysis:
    """Conditioning of M(q) at one configuration.

    Attributes:
        robot: Robot name.
        method: ``"crba"`` (dense M from Pinocchio, symmetric eigensolver) or
            ``"denoc-linear"`` (the O(n) path of `gimwatch.metrics.linear_analysis`: κ by
            Lanczos,
            ``eigenvalues`` only (λmin, λmax), no forward pivots).
        nv: Size of the GIM.
        q: The configuration (length nq).
        kappa: κ₂ = λmax/λmin (None when not asked for).
        kappa_equilibrated: κ_S = κ₂(D^-1/2 M D^-1/2), D = diag M (None when not asked for):
            the coupling part of κ (κ ≤ δ·κ_S), the same in any units of the coordinates.
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
    kappa_equilibrated: float | None = None

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
    massless = [dof_names[int(k)] for k in np.flatnonzero(~(np.asarray(diagonal) > 0))]
    if massless:
        raise ConditioningError(
            f"{source}: M(q) of {name} is singular: "
            f"{len(massless)} coordinate(s) move no mass "
            f"({', '.join(massless[:4])}{', ...' if len(massless) > 4 else ''}); "
            "give the links they move an <inertial>"
        )


def check_robot_gim(robot: Robot, M: np.ndarray) -> np.ndarray:
    """Check M(q) of ``robot`` like `check_gim`, naming joints.

    Raises:
        ConditioningError: A coordinate moves no mass (M singular), naming the URDF and the
            coordinates; or M is not a valid GIM.
    """
    check_massless(np.diag(M), robot.dof_names, name=robot.name, source=robot.source)
    return check_gim(M)


#: The scalar metrics of a [`GimAnalysis`][gimwatch.metrics.dense_analysis.GimAnalysis], in its
#: field order (registry names).
ANALYSIS_METRICS = (
    "kappa",
    "diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "kappa_equilibrated",
)


def analysis_record(
    state: GimState,
    metrics: Sequence[str],
    *,
    name: str,
    nv: int,
    q: npt.ArrayLike,
    dof_names: Sequence[str],
    method: str,
) -> GimAnalysis:
    """The `GimAnalysis` of one state: the named registry metrics, the others None.

    The spectrum is the full one when M is formed, else (the O(n) path) λmin and λmax.
    """
    values = {key: None for key in ANALYSIS_METRICS} | evaluate(metrics, state)
    diag = state.diag
    if "kappa" in metrics:
        warn_if_ill_conditioned(values["kappa"], where=name)
        extremes: tuple[float, float] | tuple[None, None] = state.extremes
        spectrum: np.ndarray | tuple[float, ...] = (
            state.eigenvalues if state.linear is None else state.extremes
        )
    else:
        extremes, spectrum = (None, None), ()
    lambda_min, lambda_max = extremes
    return GimAnalysis(
        robot=name,
        nv=nv,
        q=tuple(float(x) for x in np.asarray(q, dtype=float)),
        **values,
        lambda_min=lambda_min,
        lambda_max=lambda_max,
        eigenvalues=tuple(float(x) for x in spectrum),
        diagonal=tuple(float(x) for x in diag),
        max_diagonal_dof=dof_names[int(np.argmax(diag))],
        min_diagonal_dof=dof_names[int(np.argmin(diag))],
        method=method,
    )


def analyze_configuration(robot: Robot, q: npt.ArrayLike, *, data=None) -> GimAnalysis:
    """Compute κ, δ, both pivot ratios, κ_S and the spectrum of M(q) (dense M, Pinocchio's CRBA)."""
    q = as_configuration(robot, q)
    M = check_robot_gim(robot, gim(robot, q, data=data))
    state = GimState(PinocchioSource(robot, data), q, full=True, matrix=M)
    return analysis_record(
        state,
        ANALYSIS_METRICS,
        name=robot.name,
        nv=robot.nv,
        q=q,
        dof_names=robot.dof_names,
        method="crba",
    )
