"""The armature calculator: target met when applied (Pinocchio, MuJoCo), minimal, priced."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.bench import mujoco_peer
from gimwatch.errors import InputError
from gimwatch.explain.armature import minimal_armature
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import chain_robot, load_robot
from gimwatch.model.sampling import random_configurations


def _kappa(robot, q, added):
    model = pin.Model(robot.model)
    model.armature = np.asarray(model.armature) + added
    w = np.linalg.eigvalsh(pin.crba(model, model.createData(), q))
    return w[-1] / w[0]


@pytest.fixture(scope="module")
def ur5():
    return load_robot("ur5")


@pytest.fixture(scope="module")
def configurations(ur5):
    return random_configurations(ur5, 20, seed=1)


def test_uniform_armature_meets_the_target_and_is_minimal(ur5, configurations):
    target = 0.5 * max(_kappa(ur5, q, 0.0) for q in configurations)
    plan = minimal_armature(ur5, configurations, target)
    a = plan.armature[0]
    assert all(x == a for x in plan.armature) and a > 0
    assert max(plan.kappa_after) <= target
    assert max(plan.kappa_after) == pytest.approx(target, rel=1e-8)  # tight: minimal
    less = np.full(ur5.nv, a * (1 - 1e-6))
    assert max(_kappa(ur5, q, less) for q in configurations) > target
    assert max(plan.kappa_before) == pytest.approx(2 * target, rel=1e-12)
    assert all(c > 0 for c in plan.qdd_change)


def test_no_armature_when_the_target_already_holds(ur5, configurations):
    target = 2 * max(_kappa(ur5, q, 0.0) for q in configurations)
    plan = minimal_armature(ur5, configurations, target, per_joint=True)
    assert plan.total == 0.0 and plan.qdd_change == (0.0,) * len(configurations)


def test_per_joint_armature_is_feasible_within_its_certified_gap(ur5, configurations):
    target = 0.5 * max(_kappa(ur5, q, 0.0) for q in configurations)
    uniform = minimal_armature(ur5, configurations, target)
    plan = minimal_armature(ur5, configurations, target, per_joint=True, rtol=1e-4)
    assert max(plan.kappa_after) <= target
    assert plan.lower_bound <= plan.total <= plan.lower_bound * (1 + 1e-4) * (1 + 1e-8)
    assert plan.total <= uniform.total * (1 + 1e-8)
    # an independent check of minimality: scaling the answer down breaks the target
    added = np.array(plan.armature) * (1 - 1e-3)
    assert max(_kappa(ur5, q, added) for q in configurations) > target


def test_per_joint_is_much_cheaper_than_uniform_on_the_paper_chain():
    robot = chain_robot(chain_spec(6))
    qs = np.zeros((1, 6))
    target = 0.5 * _kappa(robot, qs[0], 0.0)
    uniform = minimal_armature(robot, qs, target)
    plan = minimal_armature(robot, qs, target, per_joint=True, rtol=1e-4)
    assert max(plan.kappa_after) <= target
    assert plan.total < uniform.total


@pytest.mark.skipif(not mujoco_peer.available(), reason="MuJoCo is an optional peer")
def test_mujoco_mass_matrix_with_armature_meets_the_target():
    """MuJoCo's own M with ``dof_armature`` set (a spatial chain: meshes need no files)."""
    robot = chain_robot(chain_spec(5, axes="spatial", mass_kg=[3, 2, 1.5, 1, 0.5]))
    configurations = random_configurations(robot, 10, seed=2)
    target = 0.5 * max(_kappa(robot, q, 0.0) for q in configurations)
    plan = minimal_armature(robot, configurations, target, per_joint=True, rtol=1e-4)
    model = mujoco_peer.load_model(robot.urdf_xml, np.zeros(3))
    model.dof_armature[:] = plan.armature
    kappas = []
    for q in configurations:
        w = np.linalg.eigvalsh(mujoco_peer.mass_matrix(model, q))
        kappas.append(w[-1] / w[0])
    np.testing.assert_allclose(kappas, plan.kappa_after, rtol=1e-6)
    assert max(kappas) <= target * (1 + 1e-6)


@pytest.mark.parametrize("target", [1.0, 0.5, float("nan"), float("inf")])
def test_bad_targets_are_refused(ur5, target):
    with pytest.raises(InputError, match="target must be a number > 1"):
        minimal_armature(ur5, np.zeros((1, 6)), target)
