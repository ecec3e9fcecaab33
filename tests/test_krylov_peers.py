import numpy as np
import pinocchio as pin
import pytest
import scipy.linalg
from closed_forms import straight_chain_extreme_eigenvalues

from gimwatch.bench.krylov_peers import gim_inverse_operator, gim_operator, kappa_matrix_free
from gimwatch.errors import InputError
from gimwatch.model.inertia import gim
from gimwatch.model.robots import load_robot, neutral_configuration
from gimwatch.model.sampling import random_configurations


@pytest.mark.parametrize("spec", ["chain:7", "ur5", "panda"])
def test_operators_are_crba_products_and_solves(spec):
    robot = load_robot(spec)
    q = random_configurations(robot, 1, seed=3)[0]
    M = gim(robot, q)
    x = np.random.default_rng(1).standard_normal(robot.nv)
    np.testing.assert_allclose(gim_operator(robot, q).matvec(x), M @ x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(
        gim_inverse_operator(robot, q).matvec(x), np.linalg.solve(M, x), rtol=1e-9, atol=1e-12
    )


def test_gravity_is_off_but_the_robot_keeps_it():
    robot = load_robot("chain:3")
    q = neutral_configuration(robot)
    op = gim_operator(robot, q)
    np.testing.assert_allclose(op.matvec(np.zeros(3)), np.zeros(3), atol=0)
    assert robot.model.gravity.linear[2] == pytest.approx(-9.81)


def _dense_kappa(robot, q) -> float:
    """κ from Pinocchio's CRBA and LAPACK (scipy.linalg.eigh): not gimwatch's code path."""
    M = pin.crba(robot.model, robot.model.createData(), q)
    values = scipy.linalg.eigh(M, eigvals_only=True)
    return float(values[-1] / values[0])


@pytest.mark.parametrize("spec", ["chain:1", "chain:2", "chain:20", "ur5", "solo12"])
def test_kappa_matrix_free_matches_the_eigensolver(spec):
    robot = load_robot(spec)
    q = random_configurations(robot, 1, seed=5)[0]
    result = kappa_matrix_free(robot, q, seed=2, tol=1e-12)
    assert result.kappa == pytest.approx(_dense_kappa(robot, q), rel=1e-8)
    assert result.products > 0 and isinstance(result.kappa, float)


def test_straight_chain_needs_a_random_start_and_gets_it():
    # κ of the straight paper chain is about 4 n^4 (the README's demo finding).
    robot = load_robot("chain:30")
    q = neutral_configuration(robot)
    result = kappa_matrix_free(robot, q, seed=0, tol=1e-12)
    assert result.kappa == pytest.approx(_dense_kappa(robot, q), rel=1e-8)


def test_warm_start_from_a_nearby_sample_gives_the_same_kappa():
    robot = load_robot("chain:25")
    q0 = random_configurations(robot, 1, seed=0)[0]
    first = kappa_matrix_free(robot, q0, seed=0, tol=1e-12)
    q1 = q0 + 0.01
    warm = kappa_matrix_free(robot, q1, tol=1e-12, start=(first.vector_max, first.vector_min))
    assert warm.kappa == pytest.approx(_dense_kappa(robot, q1), rel=1e-8)


def test_bad_tolerance_is_refused_with_its_value():
    robot = load_robot("chain:3")
    with pytest.raises(InputError, match=r"^tol must be finite and >= 0, got -1.0$"):
        kappa_matrix_free(robot, np.zeros(3), tol=-1.0)


def test_arpack_kappa_of_the_clustered_straight_chain_is_tight():
    # the hard case (smallest eigenvalues within relative gaps ~1/n²), against the banded
    # closed-form pencil of tests/closed_forms.py: measured 9e-15 at tol = 1e-10; ARPACK
    # stopped at tol = 1e-3 is off by 7e-4
    n = 200
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    result = kappa_matrix_free(load_robot(f"chain:{n}"), np.zeros(n), seed=0, tol=1e-10)
    assert result.kappa == pytest.approx(lambda_max / lambda_min, rel=1e-12)
    assert result.lambda_min == pytest.approx(lambda_min, rel=1e-12)
