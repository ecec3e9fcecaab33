"""How well the diagonal ratio δ tracks κ along a series: the one set of statistics.

The watch's summaries, the survey's random samples and the survey's trajectories all use
[`estimator_quality`][gimwatch.watch.watch.estimator_quality], under one rule for the first sample
(t0):

* α = κ(t0)/δ(t0) is fixed at t0 (Shah & Saha 2013, Eq. 15), so αδ equals κ there by
  construction; the relative errors |αδ − κ|/κ are taken over the **later** samples only.
* The correlations — Pearson of log δ with log κ, Spearman of δ with κ — use **every**
  sample, t0 included: they do not depend on α. They are NaN with fewer than 3 samples or
  when δ or κ is constant.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

__all__ = ["EstimatorQuality", "correlations", "estimator_quality", "relative_errors"]


@dataclass(frozen=True)
class EstimatorQuality:
    """How well δ tracks κ along a series (α from t0 only, never tuned).

    Attributes:
        samples: Number of samples compared, t0 included.
        alpha: α = κ(t0)/δ(t0) (Eq. 15).
        pearson_log: Pearson correlation of log δ vs log κ.
        spearman: Spearman rank correlation of δ vs κ.
        median_relative_error: median |αδ - κ| / κ after t0.
        max_relative_error: max |αδ - κ| / κ after t0.
        max_kappa: Largest κ seen.
        max_scaled_diagonal_ratio: Largest αδ seen.
    """

    samples: int
    alpha: float
    pearson_log: float
    spearman: float
    median_relative_error: float
    max_relative_error: float
    max_kappa: float
    max_scaled_diagonal_ratio: float


def correlations(delta: npt.ArrayLike, kappa: npt.ArrayLike) -> tuple[float, float]:
    """Pearson r(log δ, log κ) and Spearman ρ(δ, κ); NaN with < 3 samples or a constant one."""
    import scipy.stats

    delta, kappa = np.asarray(delta, dtype=float), np.asarray(kappa, dtype=float)
    if delta.size < 3 or np.ptp(delta) == 0 or np.ptp(kappa) == 0:
        return math.nan, math.nan
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", scipy.stats.ConstantInputWarning)
        pearson = scipy.stats.pearsonr(np.log(delta), np.log(kappa)).statistic
        spearman = scipy.stats.spearmanr(delta, kappa).statistic
    return float(pearson), float(spearman)


def relative_errors(kappa: npt.ArrayLike, scaled: npt.ArrayLike) -> np.ndarray:
    """|αδ − κ| / κ at the samples after t0 (at t0 it is 0 by construction of α)."""
    kappa, scaled = np.asarray(kappa, dtype=float), np.asarray(scaled, dtype=float)
    return np.abs(scaled[1:] - kappa[1:]) / kappa[1:]


def estimator_quality(kappa: npt.ArrayLike, delta: npt.ArrayLike) -> EstimatorQuality | None:
    """Compare δ and αδ (α = κ₀/δ₀) with κ along a series; None with fewer than 2 samples."""
    kappa, delta = np.asarray(kappa, dtype=float), np.asarray(delta, dtype=float)
    if kappa.size < 2:
        return None
    alpha = kappa[0] / delta[0]
    scaled = alpha * delta
    error = relative_errors(kappa, scaled)
    pearson, spearman = correlations(delta, kappa)
    return EstimatorQuality(
        samples=int(kappa.size),
        alpha=float(alpha),
        pearson_log=pearson,
        spearman=spearman,
        median_relative_error=float(np.median(error)),
        max_relative_error=float(np.max(error)),
        max_kappa=float(np.max(kappa)),
        max_scaled_diagonal_ratio=float(np.max(scaled)),
    )
