import numpy as np
import pinocchio as pin
import pytest

from gimwatch.bench import mujoco_peer
from gimwatch.errors import InputError
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene

GRAVITY = np.array([0.0, -9.81, 0.0])


@pytest.mark.parametrize("n", [4, 10, 20])
def test_mujoco_mass_matrix_equals_pinocchio_crba(n):
    robot = load_robot(f"chain:{n}")
    model = mujoco_peer.load_model(robot.urdf_xml, GRAVITY)
    assert (model.nq, model.nv) == (n, n)
    assert not model.jnt_limited.any() and not model.dof_armature.any()
    assert not model.dof_damping.any() and model.ngeom == 0
    np.testing.assert_array_equal(model.opt.gravity, GRAVITY)
    data = robot.new_data()
    for q in random_configurations(robot, 3, seed=n):
        M = np.array(pin.crba(robot.model, data, q))
        M = np.triu(M) + np.triu(M, 1).T
        got = mujoco_peer.mass_matrix(model, q)
        np.testing.assert_allclose(got, M, rtol=0, atol=1e-12 * np.abs(M).max())


def test_mujoco_rk4_follows_the_same_swinging_chain_as_gimwatch():
    n, duration = 4, 0.5
    robot = load_robot(f"chain:{n}")
    model = mujoco_peer.load_model(robot.urdf_xml, GRAVITY)
    table = {
        "robot": f"chain:{n}",
        "duration": duration,
        "sample": 0.05,
        "effects": {"gravity": {"vector": list(GRAVITY)}},
        "integrator": {"method": "DOP853", "rtol": 1e-12, "atol": 1e-12},
    }
    reference = run_scene(parse_scene(table, source="t.toml"))
    zero = np.zeros(n)
    # Same physics: both MuJoCo integrators converge to gimwatch's DOP853 trajectory at
    # their order (RK4: 4, semi-implicit Euler: 1) when the step is halved.
    for method, dt, order, tol in (("RK4", 1e-3, 4, 1e-9), ("semi-implicit-euler", 1e-4, 1, 1e-3)):
        errors = []
        for step in (dt, dt / 2):
            run = mujoco_peer.simulate(
                model, zero, zero, method=method, dt=step, duration_s=duration, sample_s=0.05
            )
            assert run.steps == round(duration / step)
            errors.append(np.abs(run.q - reference.q[-1]).max())
        assert errors[0] < tol, (method, errors)
        assert np.log2(errors[0] / errors[1]) == pytest.approx(order, abs=0.3), (method, errors)
    rk4 = mujoco_peer.simulate(
        model, zero, zero, method="RK4", dt=1e-3, duration_s=duration, sample_s=0.05
    )
    assert rk4.energy_drift < 1e-9


def test_urdf_without_robot_tag_is_refused():
    with pytest.raises(InputError, match="urdf_xml"):
        mujoco_peer.load_model("<model/>", GRAVITY)
