"""Estimator statistics (metrics/estimator_quality.py) against textbook formulas in NumPy.

Pearson's r is computed here from its definition (centred dot product over the norms) on
log δ and log κ; Spearman's ρ as Pearson on the ranks (``argsort`` twice; the series below
have no ties); the relative errors |αδ − κ|/κ after t0 with α = κ₀/δ₀ (Shah & Saha 2013,
Eq. 15). None of this goes through SciPy, which the module uses.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from gimwatch.metrics.estimator_quality import correlations, estimator_quality


def _pearson(x, y):
    x, y = x - x.mean(), y - y.mean()
    return float(x @ y / math.sqrt((x @ x) * (y @ y)))


def _ranks(x):
    return np.argsort(np.argsort(x)).astype(float)


def _series(n=40, seed=3):
    rng = np.random.default_rng(seed)
    delta = np.exp(rng.uniform(0.0, 6.0, n))  # δ over six e-folds: log and linear differ
    kappa = delta**1.7 * np.exp(rng.normal(0.0, 0.8, n))  # κ related but not a monotone map
    return kappa, delta


def test_correlations_match_the_definitions_on_logarithms_and_ranks():
    kappa, delta = _series()
    pearson, spearman = correlations(delta, kappa)
    assert pearson == pytest.approx(_pearson(np.log(delta), np.log(kappa)), abs=1e-12)
    assert spearman == pytest.approx(_pearson(_ranks(delta), _ranks(kappa)), abs=1e-12)
    # the linear Pearson differs from the log one on this series (so the test can tell them)
    assert abs(_pearson(delta, kappa) - pearson) > 0.05


def test_quality_statistics_match_hand_formulas():
    kappa, delta = _series()
    quality = estimator_quality(kappa, delta)
    alpha = kappa[0] / delta[0]
    errors = np.abs(alpha * delta[1:] - kappa[1:]) / kappa[1:]
    assert quality.samples == kappa.size
    assert quality.alpha == pytest.approx(alpha, rel=1e-15)
    assert quality.median_relative_error == pytest.approx(np.median(errors), rel=1e-12)
    assert quality.max_relative_error == pytest.approx(errors.max(), rel=1e-12)
    assert quality.max_kappa == kappa.max()
    assert quality.max_scaled_diagonal_ratio == pytest.approx((alpha * delta).max(), rel=1e-15)
    assert quality.max_scaled_diagonal_ratio != pytest.approx(delta.max(), rel=1e-3)


def test_t0_is_left_out_of_the_errors_but_counts_in_the_correlations():
    # three samples: at t0 the error is 0 by construction; the median of the two later
    # errors differs from the median of all three
    kappa = np.array([10.0, 30.0, 50.0])
    delta = np.array([2.0, 3.0, 20.0])  # α = 5: αδ = 10, 15, 100 -> errors 0.5, 1.0
    quality = estimator_quality(kappa, delta)
    assert quality.median_relative_error == pytest.approx(0.75, rel=1e-15)
    assert quality.max_relative_error == pytest.approx(1.0, rel=1e-15)
    assert quality.spearman == pytest.approx(1.0, abs=1e-15)  # δ and κ rise together
    assert quality.pearson_log == pytest.approx(_pearson(np.log(delta), np.log(kappa)), abs=1e-12)


def test_correlations_need_three_varying_samples():
    assert all(math.isnan(c) for c in correlations([1.0, 2.0], [3.0, 5.0]))
    assert all(math.isnan(c) for c in correlations([1.0, 1.0, 1.0], [3.0, 5.0, 7.0]))
    assert all(math.isnan(c) for c in correlations([1.0, 2.0, 4.0], [3.0, 3.0, 3.0]))
    assert estimator_quality([5.0], [2.0]) is None
