"""The fused, preallocated DeNOC path (LeanModel) against Pinocchio, fixed and floating bases."""

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.crosscheck import denoc_model
from gimwatch.errors import ConditioningError
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

CASES = [("chain:20", False), ("ur5", False), ("ur5", True), ("solo12", True), ("talos", True)]
GRAVITY = np.array([0.3, -9.81, 0.1])


def _setup(spec, floating):
    robot = load_robot(spec, floating=floating)
    lean = denoc_model(robot).lean()
    q = random_configurations(robot, 1, seed=3)[0]
    v, a, tau = np.random.default_rng(3).standard_normal((3, robot.nv))
    model = pin.Model(robot.model)
    model.gravity = pin.Motion(GRAVITY, np.zeros(3))
    return robot, lean, model, robot.new_data(), q, v, a, tau


@pytest.mark.parametrize(("spec", "floating"), CASES)
def test_lean_matches_pinocchio(spec, floating):
    robot, lean, model, data, q, v, a, tau = _setup(spec, floating)
    M = pin.crba(model, data, q)
    np.testing.assert_allclose(lean.gim_diagonal(q), np.diag(M), rtol=1e-12, atol=0)
    assert lean.diagonal_ratio(q) == pytest.approx(np.diag(M).max() / np.diag(M).min(), rel=1e-12)
    lean.configure(q)
    np.testing.assert_allclose(lean.gim_product(a), M @ a, rtol=1e-11, atol=1e-12 * abs(M).max())
    x = np.linalg.solve(M, a)
    np.testing.assert_allclose(lean.gim_solve(a), x, rtol=1e-9, atol=1e-11 * abs(x).max())
    reference = pin.aba(model, data, q, v, tau)
    out = np.empty(robot.nv)
    got = lean.forward_dynamics(q, v, tau, GRAVITY, out)
    assert got is out
    np.testing.assert_allclose(out, reference, rtol=1e-9, atol=1e-11 * abs(reference).max())
    reference = pin.rnea(model, data, q, v, a)
    np.testing.assert_allclose(
        lean.inverse_dynamics(q, v, a, GRAVITY),
        reference,
        rtol=1e-10,
        atol=1e-12 * abs(reference).max(),
    )


def test_lean_at_rest_without_velocity_terms():
    """v = 0 takes the short path (no bias terms): still Pinocchio's answer."""
    robot, lean, model, data, q, _, _, tau = _setup("ur5", True)
    zero = np.zeros(robot.nv)
    np.testing.assert_allclose(
        lean.forward_dynamics(q, zero, tau, GRAVITY), pin.aba(model, data, q, zero, tau), rtol=1e-10
    )


def test_lean_singular_gim_is_refused():
    """A joint that moves no mass: a zero pivot, reported, not a NaN result."""
    from gimwatch.denoc import DenocModel

    urdf = """<robot name="r"><link name="base"/>
      <link name="a"><inertial><mass value="0"/>
        <inertia ixx="0" iyy="0" izz="0" ixy="0" ixz="0" iyz="0"/></inertial></link>
      <joint name="j" type="revolute"><parent link="base"/><child link="a"/><axis xyz="0 0 1"/>
      <limit lower="-1" upper="1" effort="1" velocity="1"/></joint></robot>"""
    lean = DenocModel.from_urdf(urdf).lean()
    with pytest.raises(ConditioningError, match="singular"):
        lean.configure(np.zeros(1))


def test_watch_delta_comes_from_the_lean_kernel_and_matches_the_closed_form():
    """δ watched alone: one compiled DeNOC call per sample, equal to the rod-chain formula."""
    from conftest import planar_rod_chain_gim

    from gimwatch.watch.watch import Watch

    robot = load_robot("chain:7")
    watch = Watch(robot, ("diagonal_ratio",))
    assert watch.lean is not None
    qs = random_configurations(robot, 4, seed=11)
    for k, q in enumerate(qs):
        watch.sample(0.1 * k, q)
        d = np.diag(planar_rod_chain_gim(q, 2.2, 1.0))
        assert watch.series["diagonal_ratio"][k] == pytest.approx(d.max() / d.min(), rel=1e-12)


@pytest.mark.parametrize(("spec", "floating"), CASES)
def test_shifted_factor_solves_m_minus_sigma_and_counts_its_inertia(spec, floating):
    """After factor_shifted(σ), gim_solve gives (M − σ·1)⁻¹ y, and the factor reports every
    pivot positive exactly when σ < λmin (Sylvester's law of inertia), against Pinocchio's M."""
    from gimwatch.denoc import fused

    robot, lean, model, data, q, _, a, _ = _setup(spec, floating)
    M = pin.crba(model, data, q)
    M = np.triu(M) + np.triu(M, 1).T
    low = np.linalg.eigvalsh(M)[0]
    lean.configure(q)
    buffers = lean.compiled_operator_arguments()
    assert fused.factor_shifted(0.5 * low, *buffers)
    x = np.linalg.solve(M - 0.5 * low * np.eye(robot.nv), a)
    np.testing.assert_allclose(lean.gim_solve(a), x, rtol=1e-8, atol=1e-10 * abs(x).max())
    assert fused.factor_shifted(low * (1 - 1e-6), *buffers)
    assert not fused.factor_shifted(low * (1 + 1e-6), *buffers)
    assert not fused.factor_shifted(2.0 * low, *buffers)
