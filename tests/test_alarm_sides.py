"""Every scalar metric's alarm fires on the ill-conditioned side of its threshold, and only there.

The watch compares ``Metric.severity(value)`` (a condition-number scale: large = bad) with the
threshold. The reference here is computed apart from the registry, with NumPy on Pinocchio's
CRBA M: κ₂ by ``numpy.linalg.cond``, κ₁ for ``rcond`` (where *smaller* values are worse), the
pivots of LDLᵀ from Cholesky factors of M and of M reversed. Two samples per metric: a
threshold a factor 2 under the reference must raise the alarm, a factor 2 over must not. A
metric added to the registry without a reference here fails the first test, so its direction
and scale are stated before it can be watched.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.metrics.registry import METRICS
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch.watch import Watch


def _pivots(M: np.ndarray) -> np.ndarray:
    return np.diag(np.linalg.cholesky(M)) ** 2  # LDLᵀ's D: the squared Cholesky diagonal


#: metric -> its severity (condition-number scale) from M, computed without gimwatch
REFERENCE = {
    "kappa": lambda M: np.linalg.cond(M, 2),
    "kappa_lanczos": lambda M: np.linalg.cond(M, 2),
    "kappa_tracked": lambda M: np.linalg.cond(M, 2),
    "diagonal_ratio": lambda M: M.diagonal().max() / M.diagonal().min(),
    # αδ at its first sample is κ by construction of α = κ(t0)/δ(t0)
    "scaled_diagonal_ratio": lambda M: np.linalg.cond(M, 2),
    "pivot_ratio_forward": lambda M: _ratio(_pivots(M)),
    "pivot_ratio_backward": lambda M: _ratio(_pivots(M[::-1, ::-1])),
    "rcond": lambda M: np.linalg.cond(M, 1),  # the value is 1/κ₁: small = bad
    # κ(S), S = D^-1/2 M D^-1/2: the coupling left once the diagonal's spread is scaled out
    "kappa_equilibrated": lambda M: np.linalg.cond(_equilibrated(M), 2),
    "kappa_equilibrated_tracked": lambda M: np.linalg.cond(_equilibrated(M), 2),
}

#: metrics whose alarm needs more than M (servos, an integrator): checked where that lives
ELSEWHERE = {"stability_margin": "test_stability_metric.py"}


def _equilibrated(M: np.ndarray) -> np.ndarray:
    scale = 1.0 / np.sqrt(M.diagonal())
    return scale[:, None] * M * scale[None, :]


def _ratio(values: np.ndarray) -> float:
    return float(values.max() / values.min())


SCALARS = sorted(name for name, cls in METRICS.items() if not cls.vector and name in REFERENCE)


def test_every_scalar_metric_has_an_independent_reference():
    scalars = {name for name, cls in METRICS.items() if not cls.vector}
    assert scalars == set(REFERENCE) | set(ELSEWHERE), "state a new metric's direction here"
    for name, test_file in ELSEWHERE.items():  # that file does test this metric's alarm
        text = (Path(__file__).parent / test_file).read_text(encoding="utf-8")
        assert name in text and "alarm" in text, (name, test_file)


@pytest.fixture(scope="module")
def arm():
    robot = load_robot("ur5")
    q = random_configurations(robot, 1, seed=3)[0]
    M = pin.crba(robot.model, robot.new_data(), q)
    return robot, q, np.triu(M) + np.triu(M, 1).T


@pytest.mark.parametrize("name", SCALARS)
def test_the_alarm_fires_on_the_ill_conditioned_side_only(arm, name):
    robot, q, M = arm
    severity = REFERENCE[name](M)
    assert severity > 2  # ur5 is far enough from κ = 1 for a factor-2 margin on each side
    for factor, fires in ((0.5, True), (2.0, False)):
        watch = Watch(
            robot, (name,), alarm_metric=name, alarm_threshold=factor * severity, warn=False
        )
        alarm = watch.sample(0.0, q)
        assert (alarm is not None) == fires, (name, factor, severity)
        assert len(watch.alarms) == int(fires)
