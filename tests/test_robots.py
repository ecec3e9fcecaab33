import numpy as np
import pinocchio as pin
import pytest

from gimwatch.errors import InputError, RobotError, URDFError
from gimwatch.model.robots import load_robot, neutral_configuration
from gimwatch.model.sampling import random_configurations


def test_chain_spec_loads_the_paper_chain():
    robot = load_robot("chain:10")
    assert (robot.name, robot.nv, robot.nq, robot.floating) == ("chain_10", 10, 10, False)
    assert robot.chain is not None and robot.chain.masses_kg == (2.2,) * 10


def test_floating_base_adds_a_free_flyer():
    robot = load_robot("ur5", floating=True)
    assert (robot.nv, robot.nq) == (12, 13)
    assert robot.joint_names[0] == "root_joint"
    assert robot.dof_names[:2] == ("root_joint[0]", "root_joint[1]")
    np.testing.assert_array_equal(neutral_configuration(robot)[3:7], [0, 0, 0, 1])


@pytest.mark.parametrize("spec", ["ur5", "double_pendulum_continuous", "solo12", "tiago"])
def test_random_configurations_are_seeded_valid_and_within_limits(spec):
    robot = load_robot(spec, floating=spec == "solo12")
    qs = random_configurations(robot, 20, seed=42)
    np.testing.assert_array_equal(qs, random_configurations(robot, 20, seed=42))
    assert not np.array_equal(qs, random_configurations(robot, 20, seed=43))
    model = robot.model
    for q in qs:
        assert pin.isNormalized(model, q, 1e-12)
        bounded = np.abs(model.upperPositionLimit) < 1e10
        inside = (q >= model.lowerPositionLimit - 1e-12) & (q <= model.upperPositionLimit + 1e-12)
        assert np.all(inside | ~bounded)


@pytest.mark.parametrize(
    ("spec", "error", "message"),
    [
        (
            "ur55",
            RobotError,
            "robot 'ur55': not chain:N, a URDF or MJCF file, or an example-robot-data "
            "robot; did you mean ur5",
        ),
        (
            "UR5",
            RobotError,
            "robot 'UR5': not chain:N, a URDF or MJCF file, or an example-robot-data "
            "robot; did you mean ur5?",
        ),
        ("chain:x", InputError, "the N of chain:N must be a positive integer, got 'x'"),
        ("chain:0", InputError, "the number of links must be an integer between 1"),
        ("missing.urdf", URDFError, "missing.urdf: no such file"),
        ("cassie", RobotError, "robot 'cassie': example-robot-data ships it only as SDF"),
    ],
)
def test_bad_specs_name_what_is_wrong(spec, error, message):
    with pytest.raises(error) as info:
        load_robot(spec)
    assert str(info.value).startswith(message)


def test_a_drone_has_no_joint_on_a_fixed_base():
    assert load_robot("iris").floating  # example-robot-data's base: a free-flyer
    with pytest.raises(RobotError) as info:
        load_robot("iris", floating=False)
    assert str(info.value).startswith("robot 'iris': has no degree of freedom with a fixed base")


def test_a_directory_is_not_a_urdf(tmp_path):
    with pytest.raises(URDFError, match="is a directory"):
        load_robot(tmp_path)
