import math

import numpy as np
import pinocchio as pin
import pytest
from conftest import planar_rod_chain_gim

from gimwatch.errors import InputError
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.stress.reference_planar import PlanarChainReference, planar_reference


def _pinocchio_model(spec, gravity=(0.0, -9.81)):
    model = pin.buildModelFromXML(generate_chain_urdf(spec))
    model.gravity = pin.Motion(np.array([*gravity, 0.0]), np.zeros(3))
    return model


def _as_array(matrix):
    return np.array(matrix.tolist(), dtype=float)


@pytest.mark.parametrize("n", [1, 4, 10])
def test_gim_matches_the_closed_form_rod_sum(n):
    q = np.random.default_rng(n).uniform(-np.pi, np.pi, n)
    M = _as_array(PlanarChainReference(chain_spec(n)).gim(q))
    np.testing.assert_allclose(M, planar_rod_chain_gim(q, 2.2, 1.0), rtol=1e-13, atol=1e-13)


def test_straight_chain_diagonal_is_the_rod_about_its_end():
    # Straight uniform chain: joint 1 carries a rod of length n l and mass n m (n m (n l)^2 / 3),
    # the last joint one rod (m l^2 / 3), so delta = n^3.
    M = _as_array(PlanarChainReference(chain_spec(4)).gim(np.zeros(4)))
    assert M[0, 0] == pytest.approx(2.2 * 64 / 3, rel=1e-15)
    assert M[3, 3] == pytest.approx(2.2 / 3, rel=1e-15)


def test_single_rod_pendulum_closed_form():
    # m l^2/3 q'' = tau - m g (l/2) cos q for a rod pivoting about its end, gravity -y.
    m, l, g, q, tau = 2.2, 1.0, 9.81, 0.3, 1.5
    expected = (tau - m * g * l / 2 * math.cos(q)) / (m * l**2 / 3)
    got = planar_reference(chain_spec(1), [q], [0.7], [tau])
    assert got[0] == pytest.approx(expected, rel=1e-15)


@pytest.mark.parametrize("n", [2, 5, 9])
def test_forward_dynamics_agrees_with_pinocchio_aba(n):
    rng = np.random.default_rng(10 + n)
    spec = chain_spec(
        n,
        mass_kg=rng.uniform(0.5, 3.0, n),
        length_m=rng.uniform(0.3, 1.5, n),
        radius_m=rng.uniform(0.0, 0.05, n),
    )
    q, v, tau = rng.uniform(-2, 2, n), rng.uniform(-1, 1, n), rng.uniform(-5, 5, n)
    model = _pinocchio_model(spec)
    expected = pin.aba(model, model.createData(), q, v, tau)
    got = PlanarChainReference(spec).forward_dynamics(q, v, tau)
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12 * np.abs(expected).max())


def test_bias_is_pinocchio_nonlinear_effects():
    spec = chain_spec(6)
    rng = np.random.default_rng(4)
    q, v = rng.uniform(-2, 2, 6), rng.uniform(-1, 1, 6)
    model = _pinocchio_model(spec)
    expected = pin.nonLinearEffects(model, model.createData(), q, v)
    got = np.array([float(b) for b in PlanarChainReference(spec).bias(q, v)])
    np.testing.assert_allclose(got, expected, rtol=1e-12, atol=1e-12)


def test_non_planar_chain_is_refused():
    with pytest.raises(
        InputError,
        match=r"^the chain must be planar with revolute joints about z \(axes='planar'\), "
        r"got 'spatial'$",
    ):
        PlanarChainReference(chain_spec(3, axes="spatial"))


def test_wrong_length_q_is_refused():
    with pytest.raises(InputError, match=r"^q must be a finite vector of 3 numbers, got \(2,\)$"):
        planar_reference(chain_spec(3), [0.0, 0.0], [0, 0, 0], [0, 0, 0])
