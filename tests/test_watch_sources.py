"""The watch's sources of M: MuJoCo's M against gimwatch's CRBA, the given-matrix holder."""

from pathlib import Path

import mujoco
import numpy as np
import pytest

from gimwatch.errors import GimwatchError
from gimwatch.model.inertia import gim
from gimwatch.model.mujoco_model import _joint_maps, compile_robot
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch.sources import GivenMatrix, MujocoSource, robot_from_model


def mjcf_path(name: str) -> str:
    return str(Path(__file__).parent / "data" / "mjcf" / f"{name}.xml")


#: (robot spec, floating): URDF from example-robot-data, MJCF fixed base, MJCF free base.
ROBOTS = [
    ("ur5", False),
    (mjcf_path("panda"), False),
    (mjcf_path("solo12"), True),
]


def _pair(spec, floating, seed=3):
    """Robot, MjModel, MjData at a random configuration after mj_forward, and that q."""
    robot = load_robot(spec, floating=floating)
    model = compile_robot(robot)
    data = mujoco.MjData(model)
    q = random_configurations(robot, 1, seed=seed)[0]
    qpos = np.array(model.qpos0)
    _joint_maps(robot, model, q, qpos, np.zeros((model.nv, robot.nv)))
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    return robot, model, data, q


@pytest.mark.parametrize(("spec", "floating"), ROBOTS, ids=[s for s, _ in ROBOTS])
def test_mujoco_m_in_robot_coordinates_is_gimwatch_crba(spec, floating):
    robot, model, data, q = _pair(spec, floating)
    reference = gim(robot, q)
    source = MujocoSource(model, data, robot=robot)
    M = source.gim()
    scale = np.abs(reference).max()
    np.testing.assert_allclose(M, reference, rtol=0, atol=1e-12 * scale)
    np.testing.assert_allclose(source.gim_diagonal(), np.diag(reference), rtol=1e-12)
    assert source.dof_names == robot.dof_names
    # from MuJoCo's own coordinates: a permutation and a rotation, so the same κ and δ
    plain = MujocoSource(model, data).gim()
    kappa = np.linalg.cond(reference)
    assert np.linalg.cond(plain) == pytest.approx(kappa, rel=1e-9)
    assert np.diag(plain).max() / np.diag(plain).min() == pytest.approx(
        np.diag(reference).max() / np.diag(reference).min(), rel=1e-12
    )


def test_a_pinocchio_model_maps_like_its_robot():
    robot, model, data, q = _pair(mjcf_path("solo12"), True)
    from_robot = MujocoSource(model, data, robot=robot).gim()
    from_model = MujocoSource(model, data, robot=robot.model).gim()
    np.testing.assert_array_equal(from_model, from_robot)
    reference = gim(robot, q)  # Pinocchio's CRBA: the mapping is right, not only the same
    np.testing.assert_allclose(from_model, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


def test_armature_is_on_the_diagonal_and_can_be_removed():
    robot, model, data, q = _pair("ur5", False)
    armature = np.linspace(0.1, 0.6, model.nv)
    model.dof_armature[:] = armature
    mujoco.mj_forward(model, data)
    reference = gim(robot, q)
    with_armature = MujocoSource(model, data, robot=robot)
    np.testing.assert_allclose(with_armature.gim(), reference + np.diag(armature), atol=1e-12)
    np.testing.assert_allclose(
        with_armature.gim_diagonal(), np.diag(reference) + armature, rtol=1e-12
    )
    without = MujocoSource(model, data, robot=robot, armature=False)
    np.testing.assert_allclose(without.gim(), reference, atol=1e-12)
    np.testing.assert_allclose(without.gim_diagonal(), np.diag(reference), rtol=1e-12)


def test_m_at_a_given_qpos_leaves_the_users_data_alone():
    robot, model, data, q = _pair(mjcf_path("panda"), False, seed=5)
    _, _, _, q_other = _pair(mjcf_path("panda"), False, seed=6)
    qpos_other = np.array(model.qpos0)
    _joint_maps(robot, model, q_other, qpos_other, np.zeros((model.nv, robot.nv)))
    source = MujocoSource(model, data, robot=robot)
    qpos_before, m_before = data.qpos.copy(), data.M.copy()
    np.testing.assert_allclose(source.gim(qpos_other), gim(robot, q_other), atol=1e-12)
    np.testing.assert_allclose(source.gim_diagonal(qpos_other), np.diag(gim(robot, q_other)))
    np.testing.assert_array_equal(data.qpos, qpos_before)
    np.testing.assert_array_equal(data.M, m_before)
    np.testing.assert_allclose(source.gim(), gim(robot, q), atol=1e-12)


def test_after_mj_step_data_holds_m_where_the_step_started():
    _, model, data, _ = _pair("ur5", False)
    data.qvel[:] = 1.0
    start = data.qpos.copy()
    mujoco.mj_step(model, data)
    assert not np.array_equal(data.qpos, start)
    source = MujocoSource(model, data)
    np.testing.assert_array_equal(source.gim(), source.gim(start))
    assert np.abs(source.gim(data.qpos) - source.gim()).max() > 1e-9


def test_given_matrix_holds_what_it_is_given():
    source = GivenMatrix(2)
    source.hold_matrix([[2.0, 0.5], [0.5, 1.0]])
    np.testing.assert_array_equal(source.gim_diagonal(), [2.0, 1.0])
    source.hold_diagonal([3.0, 1.5])
    np.testing.assert_array_equal(source.gim_diagonal(), [3.0, 1.5])
    assert source.dof_names == ("dof0", "dof1")


def _message(call) -> str:
    with pytest.raises(GimwatchError) as info:
        call()
    text = str(info.value)
    assert "\n" not in text
    return text


def test_bad_sources_are_named_in_one_line():
    robot, model, data, _ = _pair("ur5", False)
    other = mujoco.MjData(compile_robot(load_robot(mjcf_path("panda"))))
    assert _message(lambda: MujocoSource(data, data)) == (
        "model must be a mujoco.MjModel, got 'mujoco._structs.MjData'"
    )
    assert _message(lambda: MujocoSource(model, model)) == (
        "data must be a mujoco.MjData, got 'mujoco._structs.MjModel'"
    )
    assert _message(lambda: MujocoSource(model, other)) == (
        "data must be the MjData of this MjModel (mujoco.MjData(model)), "
        "got 'an MjData of another model (nq = 9, nv = 9)'"
    )
    fresh = MujocoSource(model, mujoco.MjData(model))
    assert _message(fresh.gim_diagonal) == (
        "data must be an MjData holding M, got 'one that MuJoCo never computed' "
        "(call mujoco.mj_forward(model, data) or mj_step first)"
    )
    source = MujocoSource(model, data)
    assert _message(lambda: source.gim(np.zeros(5))) == (
        "q must be a qpos of 6 numbers (MuJoCo's layout), got (5,)"
    )
    assert _message(lambda: MujocoSource(model, data, robot=load_robot("chain:6"))) == (
        "robot must be a model whose joints MuJoCo has too (by name), got \"joint 'joint_1'\""
    )
    assert _message(lambda: MujocoSource(model, data, robot="ur5")) == (
        "robot must be a gimwatch Robot or a pinocchio.Model, got 'builtins.str'"
    )
    assert _message(lambda: robot_from_model(robot)) == (
        "model must be a pinocchio.Model, got 'gimwatch.model.robots.Robot'"
    )
    held = GivenMatrix(3)
    assert _message(lambda: held.hold_matrix(np.eye(2))) == (
        "M must be a (3, 3) matrix, got 'shape (2, 2)'"
    )
    assert _message(lambda: held.hold_matrix(np.diag([1.0, np.nan, 1.0]))) == (
        "M must be finite, got 'nan at (1, 1)'"
    )
    assert _message(lambda: held.hold_diagonal([1.0, -2.0, 1.0])) == (
        "the diagonal must be finite and > 0, got '-2.0 at 1'"
    )
    assert _message(lambda: GivenMatrix(0)) == "nv must be an integer >= 1, got 0"
