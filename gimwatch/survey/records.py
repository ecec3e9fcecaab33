"""The records a survey returns: per robot, its failures, and the whole survey."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from gimwatch.survey.trajectory import TrajectorySettings, TrajectoryStatistics

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["RobotFailure", "RobotSurvey", "SurveyResult", "WorstConfiguration"]


@dataclass(frozen=True)
class WorstConfiguration:
    """One of the worst-conditioned samples of a robot."""

    sample: int
    kappa: float
    diagonal_ratio: float
    q: tuple[float, ...]


@dataclass(frozen=True)
class RobotFailure:
    """A robot the survey could not use, with the stage (``load`` or ``gim``) and the reason."""

    spec: str
    stage: str
    reason: str


@dataclass(frozen=True)
class RobotSurvey:
    """The survey of one robot (see the module docstring for the definitions).

    Attributes:
        name: Robot name.
        spec: Specification it was loaded from.
        nv: Size of the GIM.
        floating: Whether the base is a free flyer.
        note: Why the base differs from the request (drones with no joint), else "".
        dof_names: Coordinate names, the targets of the ``*_dof`` indices.
        sample_index: Index of each surveyed sample (0 = neutral), ascending.
        metrics: Per-sample values keyed by ``METRICS`` and ``DOF_METRICS``.
        alpha: κ/δ at the neutral sample (NaN if that sample was not computed).
        quantiles: metric -> quantile name -> value, for κ, δ and both pivot ratios.
        pearson_log: Pearson correlation of log δ with log κ (NaN if either is constant).
        spearman: Spearman rank correlation of δ with κ (NaN if either is constant).
        alpha_delta_rel_error_median: median |αδ - κ|/κ over samples 1..K.
        alpha_delta_rel_error_max: max |αδ - κ|/κ over samples 1..K.
        worst: The samples with the largest κ, worst first.
        extreme_dofs: ``DOF_METRICS`` key -> (most frequent coordinate, its frequency).
        lambda_min_on_min_diagonal: Fraction of samples where λmin's eigenvector is
            dominated by the coordinate that holds the smallest diagonal entry.
        trajectories: Along-trajectory statistics (None without trajectories).
        placeholder_limits: Joints whose placeholder limits (|limit| >= 1e3 or none) the
            random samples replaced by ±π rad / ±1 m.
        pearson_log_delta_kappa_equilibrated: Pearson correlation of log δ with log κ_S
            (κ_S = κ of D^-1/2 M D^-1/2, the coupling part of κ; NaN if either is constant).
    """

    name: str
    spec: str
    nv: int
    floating: bool
    note: str
    dof_names: tuple[str, ...]
    sample_index: np.ndarray = field(repr=False)
    metrics: dict[str, np.ndarray] = field(repr=False)
    alpha: float
    quantiles: dict[str, dict[str, float]]
    pearson_log: float
    spearman: float
    alpha_delta_rel_error_median: float
    alpha_delta_rel_error_max: float
    worst: tuple[WorstConfiguration, ...]
    extreme_dofs: dict[str, tuple[str, float]]
    lambda_min_on_min_diagonal: float
    trajectories: TrajectoryStatistics | None = None
    placeholder_limits: tuple[str, ...] = ()
    pearson_log_delta_kappa_equilibrated: float = float("nan")

    @property
    def samples(self) -> int:
        """Number of samples surveyed."""
        return int(self.sample_index.size)

    def scaled_diagonal_ratio(self) -> np.ndarray:
        """αδ at every sample (Shah & Saha 2013, Eq. 15)."""
        return self.alpha * self.metrics["diagonal_ratio"]


@dataclass(frozen=True)
class SurveyResult:
    """A survey: the robots surveyed, the robots that failed, and whether it was interrupted."""

    robots: tuple[RobotSurvey, ...]
    failures: tuple[RobotFailure, ...]
    samples: int
    seed: int
    interrupted: bool = False
    not_reached: tuple[str, ...] = ()
    trajectory_settings: TrajectorySettings | None = None

    def __repr__(self) -> str:
        """One line: how many robots were surveyed and failed, and the sampling."""
        names = [r.name for r in self.robots]
        shown = ", ".join(names[:5]) + (f", ... ({len(names) - 5} more)" if len(names) > 5 else "")
        state = ", interrupted" if self.interrupted else ""
        return (
            f"SurveyResult({len(self.robots)} robots [{shown}], {len(self.failures)} failures, "
            f"{self.samples} random samples each, seed {self.seed}{state})"
        )

    def to_dataframe(self) -> pd.DataFrame:
        """One row per (robot, sample): robot, nv, base, sample (0 = neutral) and the metrics.

        Coordinates (``*_dof``) are given by name. Needs pandas
        (``pip install 'gimwatch[pandas]'``).
        """
        from gimwatch.output.dataframe import survey_frame

        return survey_frame(self.robots)
