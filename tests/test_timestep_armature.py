"""The least armature that buys a timestep: MuJoCo stable with it, unstable with 0.9 times it,
and the LMI's answer against SciPy's independent solvers (issue 36)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
from mujoco_divergence import diverges, load
from scipy.linalg import eigh
from scipy.optimize import brentq, minimize

from gimwatch.cli import main
from gimwatch.errors import InputError
from gimwatch.explain.timestep_armature import timestep_armature
from gimwatch.model.robots import load_robot

ARMS = Path(__file__).parent / "data" / "mjcf" / "servo_arms"


def _mujoco_with(path, integrator, armature):
    model = load(path, integrator)
    model.dof_armature[:] = model.dof_armature + np.asarray(armature)
    return model


@pytest.mark.parametrize(
    ("arm", "integrator", "h", "per_joint"),
    [
        ("general_arm", "Euler", 1e-3, False),
        ("general_arm", "Euler", 1e-3, True),
        ("ur5e", "Euler", 0.025, True),
        ("gen3", "RK4", 2e-4, False),
    ],
)
def test_mujoco_is_stable_with_the_armature_and_not_with_nine_tenths(arm, integrator, h, per_joint):
    path = str(ARMS / f"{arm}.xml")
    plan = timestep_armature(load_robot(path), h, integrator, per_joint=per_joint, gravity=False)
    added = np.array(plan.armature)
    assert plan.total > 0 and min(plan.h_star_after_s) >= h  # certified by the spectral radius
    assert max(plan.h_star_before_s) < h
    assert not diverges(_mujoco_with(path, integrator, added), h)
    assert diverges(_mujoco_with(path, integrator, 0.9 * added), h)


def _ur5_system(kp):
    robot = load_robot("ur5")
    q = pin.neutral(robot.model)
    mass = pin.crba(robot.model, robot.new_data(), q)
    return robot, np.triu(mass) + np.triu(mass, 1).T


def test_uniform_armature_against_scipy_root_of_the_generalized_eigenproblem():
    # undamped symplectic Euler: stable iff ω_max(kp·I, M + aI) ≤ 2/H
    kp, h = 2000.0, 0.01
    robot, mass = _ur5_system(kp)
    plan = timestep_armature(robot, h, "Euler", kp=kp, gravity=False)
    assert plan.armature[0] > 0

    def excess(a):
        return (
            eigh(kp * np.eye(robot.nv), mass + a * np.eye(robot.nv), eigvals_only=True)[-1]
            - (2 / h) ** 2
        )

    reference = brentq(excess, 0.0, 10.0, xtol=1e-14, rtol=1e-12)
    assert plan.armature[0] == pytest.approx(reference, rel=1e-5)


def test_per_joint_least_total_against_scipy_slsqp():
    kp, kd, h = 2000.0, 5.0, 0.01
    robot, mass = _ur5_system(kp)
    plan = timestep_armature(robot, h, "Euler", kp=kp, kd=kd, gravity=False, per_joint=True)
    # SciPy's SLSQP on the same inequality written from scratch: 4(M + A) − 2hC − h²K ⪰ 0
    S = 4 * mass - 2 * h * kd * np.eye(robot.nv) - h * h * kp * np.eye(robot.nv)

    def smallest(a):
        return np.linalg.eigvalsh(S + 4 * np.diag(a))[:1]

    def gradient(a):  # ∂λmin/∂a_i = 4 w_i², w its unit eigenvector
        return 4 * np.linalg.eigh(S + 4 * np.diag(a))[1][:, :1].T ** 2

    start = np.full(robot.nv, max(0.0, -np.linalg.eigvalsh(S)[0] / 4))
    result = minimize(
        np.sum,
        start,
        jac=lambda a: np.ones_like(a),
        bounds=[(0, None)] * robot.nv,
        constraints=[{"type": "ineq", "fun": smallest, "jac": gradient}],
        method="SLSQP",
        options={"ftol": 1e-12, "maxiter": 500},
    )
    assert result.success and plan.total > 0
    assert np.linalg.eigvalsh(S + 4 * np.diag(result.x))[0] > -1e-8
    assert plan.total == pytest.approx(result.fun, rel=1e-4)
    assert plan.total < 0.9 * robot.nv * start[0]  # per joint is not the uniform answer
    assert plan.lower_bound <= result.fun * (1 + 1e-6)


def test_json_armature_dict_and_price(capsys):
    path = str(ARMS / "gen3.xml")
    argv = ["armature", path, "--timestep", "0.002", "--integrator", "Euler", "--json"]
    assert main([*argv, "--per-joint"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert set(record["armature"]) == {f"joint_{k}" for k in range(1, 8)}
    assert record["method"] == "LMI, cutting planes"
    assert record["max_stable_timestep_after_s"][0] >= 0.002
    freq = record["servo_frequency_rad_s"]["joint_7"]
    assert freq["after"] < freq["before"]
    import mujoco

    model = load(path)
    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0]
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)  # MuJoCo's M at keyframe 0, armature in
    percent = [100 * record["armature"][f"joint_{k + 1}"] / full[k, k] for k in range(7)]
    assert list(record["inertia_percent"].values()) == pytest.approx(percent, rel=1e-9)
    assert record["qdd_change"][0] > 0


def test_bad_inputs():
    robot = load_robot(str(ARMS / "gen3.xml"))
    with pytest.raises(InputError, match="per_joint"):
        timestep_armature(robot, 1e-3, "RK4", per_joint=True)
    with pytest.raises(InputError, match="timestep_s"):
        timestep_armature(robot, -1.0, "Euler")
    assert main(["armature", "ur5", "--timestep", "0.002"]) == 2  # no servos, no gains
