import numpy as np
import pinocchio as pin
import pytest
from conftest import paper_matrix

from gimwatch.errors import ConditioningError
from gimwatch.metrics.conditioning import (
    ScaledDiagonalRatio,
    check_gim,
    condition_estimate_1norm,
    condition_number,
    diagonal_ratio,
    ldlt_pivots,
    pivot_ratio_backward,
    pivot_ratio_forward,
    udut_pivots,
)
from gimwatch.model.inertia import gim
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

PHI_EQ7 = np.array([-86.6015, -48.7133, -21.6504, -5.4126])
QDD_EQ8 = np.array([-6.2189, 7.8864, -2.1226, 0.6071])
PHI_EQ9 = np.array([-86.0, -48.7, -21.6, -5.4])
QDD_EQ9 = np.array([-5.7477, 6.7586, -1.2128, 0.2696])


def test_paper_matrix_condition_number_is_1074(paper_gim):
    assert condition_number(paper_gim) == pytest.approx(1074, abs=1)
    assert diagonal_ratio(paper_gim) == pytest.approx(47.0822 / 0.7357, rel=1e-12)


def test_paper_eq9_is_reproduced_to_the_printed_digits(paper_gim):
    qdd = np.linalg.solve(paper_gim, PHI_EQ9)
    np.testing.assert_array_equal(np.round(qdd, 4), QDD_EQ9)


def test_paper_eq8_within_what_the_printed_rounding_allows(paper_gim):
    # The matrix of Eq. (7) is printed to 4 decimals; with kappa ~ 1074 that rounding alone
    # moves the solution by up to kappa * |dM| / |M|. Eq. (8) agrees within that bound.
    qdd = np.linalg.solve(paper_gim, PHI_EQ7)
    rounding = 0.5e-4 * paper_gim.shape[0] / np.linalg.norm(paper_gim, 2)
    bound = condition_number(paper_gim) * rounding * np.linalg.norm(qdd)
    assert np.linalg.norm(qdd - QDD_EQ8) <= bound
    np.testing.assert_allclose(qdd, QDD_EQ8, atol=4e-4)


def test_perturbation_magnifies_as_in_the_paper(paper_gim):
    changes = np.abs(np.linalg.solve(paper_gim, PHI_EQ9) / np.linalg.solve(paper_gim, PHI_EQ7) - 1)
    np.testing.assert_allclose(changes * 100, [7.6, 14.3, 42.9, 55.6], atol=1.0)


def test_condition_number_matches_numpy_singular_values():
    M = gim(load_robot("ur5"), random_configurations(load_robot("ur5"), 1, seed=3)[0])
    assert condition_number(M) == pytest.approx(np.linalg.cond(M, 2), rel=1e-10)


def test_pivots_forward_match_gaussian_elimination(paper_gim):
    A = paper_gim.copy()
    pivots = []
    for k in range(4):
        pivots.append(A[k, k])
        A[k + 1 :, k:] -= np.outer(A[k + 1 :, k] / A[k, k], A[k, k:])
    np.testing.assert_allclose(ldlt_pivots(paper_gim), pivots, rtol=1e-12)
    assert pivot_ratio_forward(paper_gim) == pytest.approx(max(pivots) / min(pivots), rel=1e-12)


@pytest.mark.parametrize("spec", ["chain:6", "ur5", "talos_arm", "solo12"])
def test_backward_pivots_equal_pinocchio_cholesky_decompose(spec):
    robot = load_robot(spec, floating=spec == "solo12")
    data = robot.new_data()
    q = random_configurations(robot, 1, seed=7)[0]
    M = pin.crba(robot.model, data, q).copy()
    pin.cholesky.decompose(robot.model, data)
    np.testing.assert_allclose(udut_pivots(M), data.D, rtol=1e-10)
    assert pivot_ratio_backward(M) == pytest.approx(data.D.max() / data.D.min(), rel=1e-10)


def test_one_norm_estimate_brackets_the_exact_one_norm_condition(paper_gim):
    exact = np.linalg.cond(paper_gim, 1)
    estimate = condition_estimate_1norm(paper_gim)
    assert exact / 3 <= estimate <= exact * (1 + 1e-10)


def test_scaled_diagonal_ratio_is_calibrated_once():
    estimator = ScaledDiagonalRatio()
    M0 = paper_matrix()
    alpha = estimator.calibrate(M0)
    # α = κ(M0)/δ(M0) (Eq. 15) from NumPy, not from gimwatch's condition_number/diagonal_ratio
    values, diagonal = np.linalg.eigvalsh(M0), np.diag(M0)
    kappa0 = values[-1] / values[0]
    assert alpha == pytest.approx(kappa0 / (diagonal.max() / diagonal.min()), rel=1e-12)
    assert estimator(M0) == pytest.approx(kappa0, rel=1e-12)
    assert estimator(np.diag(M0)) == pytest.approx(kappa0, rel=1e-12)
    M1 = paper_matrix() + np.diag([0.0, 0.0, 0.0, 0.5])  # a later sample: δ changes, α does not
    d1 = np.diag(M1)
    assert estimator(M1) == pytest.approx(alpha * d1.max() / d1.min(), rel=1e-12)
    with pytest.raises(ConditioningError, match="already calibrated"):
        estimator.calibrate(M0)
    with pytest.raises(ConditioningError, match="needs a full GIM"):
        ScaledDiagonalRatio()(np.diag(M0))


@pytest.mark.parametrize(
    ("matrix", "message"),
    [
        (np.ones((2, 3)), "the GIM must be a non-empty square matrix, got shape (2, 3)"),
        (np.array([[1.0, np.nan], [np.nan, 1.0]]), "the GIM must be finite"),
        (np.array([[2.0, 1.0], [0.0, 2.0]]), "the GIM must be symmetric"),
        (np.array([[1.0, 2.0], [2.0, 1.0]]), "the GIM must be positive definite"),
        (
            np.array([[1.0, 0.0], [0.0, -1.0]]),
            "the GIM must be positive definite, got diagonal entry 1",
        ),
    ],
)
def test_invalid_matrices_are_rejected(matrix, message):
    with pytest.raises(ConditioningError) as info:
        condition_number(matrix)
    assert str(info.value).startswith(message)
    with pytest.raises(ConditioningError):
        check_gim(matrix) if "definite" not in message else pivot_ratio_forward(matrix)


def test_asymmetry_beyond_round_off_is_rejected(paper_gim):
    # 1e-8 relative asymmetry is far beyond round-off (CRBA's is ~1e-16): not a GIM
    M = paper_gim.copy()
    M[0, 1] += 1e-8 * np.abs(M).max()
    with pytest.raises(ConditioningError, match="the GIM must be symmetric"):
        condition_number(M)
    M[0, 1] = M[1, 0] + 1e-13 * np.abs(M).max()  # round-off: accepted
    assert condition_number(M) > 1
