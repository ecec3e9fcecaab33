"""DeNOC's input written from a Pinocchio model: DeNOC's M equals pinocchio.crba's."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import DenocModel
from gimwatch.denoc.tree import FREE_FLYER_NAME
from gimwatch.model.denoc_input import instantaneous_urdf, urdf_of_model
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch import Watch


def _crba(model, q):
    upper = np.triu(pin.crba(model, model.createData(), q))
    return upper + np.triu(upper, 1).T


# kinova: continuous joints (nq = 2); solo12: a free-flyer root; talos: a floating tree
@pytest.mark.parametrize("spec", ["ur5", "kinova", "solo12", "talos"])
def test_urdf_of_a_pinocchio_model_gives_its_m(spec):
    model = load_robot(spec).model
    floating = "FreeFlyer" in model.joints[1].shortname()
    order = [
        FREE_FLYER_NAME if floating and k == 1 else model.names[k] for k in range(1, model.njoints)
    ]
    denoc = DenocModel.from_urdf(urdf_of_model(model), floating=floating, joint_order=order)
    for q in random_configurations(load_robot(spec), 3, seed=2):
        M = _crba(model, q)
        np.testing.assert_allclose(denoc.gim(q), M, rtol=0, atol=1e-12 * np.abs(M).max())


def test_instantaneous_urdf_reads_continuous_joints_as_cos_sin():
    model = load_robot("kinova").model
    q = random_configurations(load_robot("kinova"), 1, seed=4)[0]
    instant = instantaneous_urdf(model, q)
    assert instant.q.size == model.nq  # no ball or free joint: the same coordinates
    denoc = DenocModel.from_urdf(instant.urdf, joint_order=instant.joint_order)
    M = _crba(model, q)
    np.testing.assert_allclose(denoc.gim(instant.q), M, rtol=0, atol=1e-12 * np.abs(M).max())


@pytest.mark.parametrize("spec", ["kinova", "solo12"])
def test_from_model_watches_on_denocs_compiled_path_with_crbas_values(spec):
    robot = load_robot(spec)
    watch = Watch.from_model(robot.model, ("diagonal_ratio", "kappa_tracked"))
    assert watch.lean is not None  # the URDF DeNOC reads was written from the model
    for t, q in enumerate(random_configurations(robot, 3, seed=6)):
        M = _crba(robot.model, q)
        eigenvalues, diagonal = np.linalg.eigvalsh(M), np.diag(M)
        watch.sample(float(t), q)
        arrays = watch.arrays()
        delta = diagonal.max() / diagonal.min()
        assert arrays["watch_diagonal_ratio"][-1] == pytest.approx(delta, rel=1e-12)
        kappa = eigenvalues[-1] / eigenvalues[0]
        assert arrays["watch_kappa_tracked"][-1] == pytest.approx(kappa, rel=1e-9)


def test_a_model_with_a_joint_denoc_lacks_has_no_urdf():
    model = pin.Model()
    model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "planar")
    assert urdf_of_model(model) == ""
