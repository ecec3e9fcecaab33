"""Contracts the type checker made explicit (issue 38: mypy on the whole library).

Where mypy found an optional input used as if always given, the code now says what is
missing in one line instead of a ``TypeError`` about ``NoneType``; where it found a wrong
annotation, the function is checked against what it is really given. The NumPy DeNOC
forward dynamics, whose optional arguments were reorganised for the checker, is compared
with Pinocchio's ABA.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import recursions
from gimwatch.errors import InputError, SceneError
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.model.mjcf_compiled import mujoco_message
from gimwatch.model.robots import load_robot
from gimwatch.simulation.scene_integrator import IntegratorSpec, check_steps

_GRAVITY = np.array([0.0, 0.0, -9.81])


def test_mujoco_message_reads_the_text_the_sandbox_passes():
    # the compile sandbox hands over the child's error text (annotated as an exception before)
    mujoco = pytest.importorskip("mujoco")
    with pytest.raises(ValueError) as refused:
        mujoco.MjSpec.from_string(
            '<mujoco><worldbody><body><geom typo="x"/></body></worldbody></mujoco>'
        )
    assert mujoco_message(str(refused.value)) == (
        "Schema violation: unrecognized attribute: 'typo' (element 'geom', line 1)"
    )


def test_a_fixed_step_integrator_without_dt_is_named():
    with pytest.raises(SceneError, match=r"^scene: integrator\.dt: is required by the fixed"):
        check_steps("scene", IntegratorSpec(method="RK4"), 1.0)
    check_steps("scene", IntegratorSpec(method="RK4", dt=1e-3), 1.0)  # the scene path


@pytest.mark.parametrize("floating", [False, True])
def test_numpy_forward_dynamics_matches_pinocchio_aba(floating):
    robot = load_robot("ur5", floating=floating)
    dm = denoc_model(robot)
    rng = np.random.default_rng(3)
    q = pin.randomConfiguration(robot.model, -np.ones(robot.nq), np.ones(robot.nq))
    v, tau = rng.normal(size=robot.nv), rng.normal(size=robot.nv)
    qd, tau_internal = dm.to_internal("v", v), dm.to_internal("tau", tau)
    root_v = qd[:6] if floating else None  # the free-flyer's (v, ω) in its own frame
    body_qd = np.concatenate([[0.0], qd[6:] if floating else qd])
    qdd, _ = recursions.forward_dynamics(
        dm.tree, dm._kinematics(q), body_qd, tau_internal, root_v, _GRAVITY
    )
    expected = pin.aba(robot.model, robot.model.createData(), q, v, tau)
    np.testing.assert_allclose(dm.to_public(qdd), expected, rtol=1e-9, atol=1e-9)


def test_numpy_dynamics_name_a_missing_velocity():
    robot = load_robot("ur5", floating=True)
    dm = denoc_model(robot)
    q = pin.neutral(robot.model)
    kin, tau = dm._kinematics(q), np.zeros(robot.nv)
    with pytest.raises(InputError, match=r"^qd must be"):
        recursions.forward_dynamics(dm.tree, kin, None, tau, np.zeros(6), _GRAVITY)
    with pytest.raises(InputError, match=r"^root_v must be"):
        recursions.forward_dynamics(dm.tree, kin, np.zeros(dm.tree.size), tau, None, _GRAVITY)


def test_kinematics_of_a_ball_joint_needs_its_pose(tmp_path):
    path = tmp_path / "pendulum.xml"
    path.write_text(
        '<mujoco><worldbody><body name="bob" pos="0 0 1"><joint name="ball" type="ball"/>'
        '<geom type="capsule" fromto="0 0 0 0 0 -0.5" size="0.02" mass="1"/></body>'
        "</worldbody></mujoco>"
    )
    tree = denoc_model(load_robot(str(path))).tree
    ones, zeros = np.ones(tree.size), np.zeros(tree.size)
    with pytest.raises(InputError, match=r"^free_pose must be"):
        recursions.kinematics(tree, ones, zeros, zeros, None, None)
