"""Stability of a servoed robot: h* against closed forms on paper, and bad inputs (issue 36)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from gimwatch.cli import main
from gimwatch.errors import InputError
from gimwatch.stability import stability
from gimwatch.stability.linear_system import LinearSystem
from gimwatch.stability.timestep import critical_mode, max_stable_timestep

ARMS = Path(__file__).parent / "data" / "mjcf" / "servo_arms"


def _servo(m: float, k: float, explicit: float = 0.0, joint: float = 0.0) -> LinearSystem:
    """A one-joint servo: inertia m, stiffness k, actuator and joint damping."""
    return LinearSystem(
        np.array([[m]]), np.array([[k]]), np.array([[explicit]]), np.array([[joint]])
    )


def _scalar_run(m, k, c_explicit, c_joint, h, integrator, steps=4000) -> float:
    """The scalar recurrence written out by hand (no matrices): |x| after ``steps`` steps."""
    q, v = 1.0, 0.0
    c = c_explicit + c_joint
    implicit = {"Euler": c_joint, "implicitfast": c, "semi-implicit-euler": 0.0}[integrator]
    for _ in range(steps):
        if abs(q) > 1e6:
            break
        a = -(k * q + c * v) / (m + h * implicit)
        v = v + h * a
        q = q + h * v
    size = abs(q) + abs(v) * h
    return size if np.isfinite(size) else np.inf


M, K = 0.3, 1200.0
OMEGA = np.sqrt(K / M)


def test_undamped_symplectic_euler_is_two_over_omega():
    h = max_stable_timestep(_servo(M, K), "semi-implicit-euler")
    assert h == pytest.approx(2.0 / OMEGA, rel=1e-6)
    assert max_stable_timestep(_servo(M, K), "Euler") == pytest.approx(2.0 / OMEGA, rel=1e-6)


@pytest.mark.parametrize("c", [0.5, 5.0, 50.0])
def test_explicit_damping_closed_form(c):
    # Jury's test on z² − (2 − hc/m − h²k/m) z + (1 − hc/m): h²k + 2hc < 4m
    expected = 4 * M / (c + np.sqrt(c * c + 4 * K * M))
    for integrator in ("Euler", "semi-implicit-euler"):  # Euler: actuator damping explicit
        h = max_stable_timestep(_servo(M, K, explicit=c), integrator)
        assert h == pytest.approx(expected, rel=1e-6)
        assert _scalar_run(M, K, c, 0, 0.99 * h, integrator) < 1.0
        assert _scalar_run(M, K, c, 0, 1.01 * h, integrator) > 1e3
    assert critical_mode(_servo(M, K, explicit=c), "Euler", h).limited_by == (
        "explicit damping" if c >= 5 else "stiffness"
    )


@pytest.mark.parametrize("c", [0.5, 5.0, 50.0])
def test_implicit_damping_closed_form(c):
    # (m + hc) a = −kq − cv: h²k < 4m + 2hc, so damping now raises h*
    expected = (c + np.sqrt(c * c + 4 * K * M)) / K
    assert max_stable_timestep(_servo(M, K, explicit=c), "implicitfast") == pytest.approx(
        expected, rel=1e-6
    )
    assert max_stable_timestep(_servo(M, K, explicit=c), "implicit") == pytest.approx(
        expected, rel=1e-6
    )
    h = max_stable_timestep(_servo(M, K, joint=c), "Euler")  # joint damping: implicit in Euler
    assert h == pytest.approx(expected, rel=1e-6)
    assert _scalar_run(M, K, 0, c, 0.99 * h, "Euler") < 1.0
    assert _scalar_run(M, K, 0, c, 1.01 * h, "Euler") > 1e3


def test_rk4_on_the_imaginary_and_real_axes():
    # |R(iy)|² = 1 − y⁶/72 + y⁸/576: the imaginary-axis limit is y = 2√2
    assert max_stable_timestep(_servo(M, K), "RK4") == pytest.approx(
        2 * np.sqrt(2) / OMEGA, rel=1e-6
    )
    # no stiffness, damping c: the real root of 1 + z/2 + z²/6 + z³/24 = 0 (NumPy's roots)
    roots = np.roots([1 / 24, 1 / 6, 1 / 2, 1])
    real = float(min(r.real for r in roots if abs(r.imag) < 1e-12))
    c = 30.0
    assert max_stable_timestep(_servo(M, 0.0, explicit=c), "RK4") == pytest.approx(
        -real * M / c, rel=1e-6
    )


def test_unstable_at_rest_and_stable_everywhere():
    assert max_stable_timestep(_servo(M, -10.0), "Euler") == 0.0  # gravity beats the servo
    assert max_stable_timestep(_servo(M, K, explicit=5.0), "implicit") < np.inf
    assert max_stable_timestep(_servo(M, 0.0, explicit=5.0), "implicitfast") == np.inf


def test_gains_on_a_urdf_match_the_two_over_omega_of_their_modes():
    # kd = 0, gravity off: symplectic Euler's h* is 2/ω_max of the pencil (kp I, M) (SciPy)
    from scipy.linalg import eigh

    from gimwatch.model.robots import load_robot

    robot = load_robot("ur5")
    record = stability(robot, integrators=["Euler"], kp=500.0, gravity=False)[0]
    import pinocchio as pin

    mass = pin.crba(robot.model, robot.new_data(), pin.neutral(robot.model))
    mass = np.triu(mass) + np.triu(mass, 1).T
    omega2 = eigh(500.0 * np.eye(robot.nv), mass, eigvals_only=True)
    assert record.max_stable_timestep_s == pytest.approx(2 / np.sqrt(omega2.max()), rel=1e-6)


def test_gravity_changes_h_star_and_can_be_left_out():
    with_g = stability("ur5", kp=50.0, kd=1.0)[0]
    without = stability("ur5", kp=50.0, kd=1.0, gravity=False)[0]
    assert with_g.max_stable_timestep_s != without.max_stable_timestep_s


def test_mjcf_servos_read_from_the_compiled_model():
    from gimwatch.model.mjcf_compiled import compile_mjcf
    from gimwatch.model.robots import load_robot
    from gimwatch.stability.analysis import held_systems

    path = str(ARMS / "geared_arm.xml")
    _, (system,), servos = held_systems(load_robot(path), gravity=False)
    model = compile_mjcf(path)
    # a position servo kp = 20 with gear 5: stiffness gear²·kp; the velocity servo kv = 0.4
    assert servos.stiffness[3] == pytest.approx(25 * 20.0)
    assert servos.explicit_damping[3] == pytest.approx(0.4)
    assert servos.stiffness[2] == pytest.approx(500.0 + 20.0)  # joint spring added
    assert servos.explicit_damping[:3] == pytest.approx([80.0, 80.0, 50.0])
    assert servos.joint_damping == pytest.approx(model.dof_damping)
    import mujoco

    data = mujoco.MjData(model)
    data.qpos[:] = model.key_qpos[0]
    mujoco.mj_forward(model, data)
    full = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, full)
    assert system.mass == pytest.approx(full, rel=1e-9, abs=1e-12)  # MuJoCo's M, armature in
    assert servos.integrator == "implicit" and servos.timestep_s == 0.004
    assert servos.not_modelled == ("friction loss",)


def test_records_and_json_rows(capsys):
    path = str(ARMS / "general_arm.xml")
    assert main(["stability", path, "--json", "--integrator", "Euler", "implicitfast"]) == 1
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert [r["integrator"] for r in rows] == ["Euler", "implicitfast"]
    assert rows[0]["stable"] is False and rows[1]["stable"] is True
    assert rows[0]["timestep_s"] == 0.002
    assert rows[0]["critical_mode"]["dof"] == "j5"
    assert rows[0]["critical_mode"]["limited_by"] == "explicit damping"
    assert "joint limits" in rows[0]["not_modelled"]
    assert main(["stability", path, "--timestep", "1e-5", "--integrator", "Euler"]) == 0


def test_batch_rows_per_robot_and_exit_status(capsys):
    assert main(["stability", str(ARMS / "ur5e.xml"), str(ARMS / "geared_arm.xml")]) == 0
    out = capsys.readouterr().out
    assert "ur5e" in out and "geared_arm" in out and "not modelled: friction loss" in out
    assert main(["stability", str(ARMS), "--integrator", "implicitfast", "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert len(rows) == 4
    assert main(["stability", str(ARMS / "ur5e.xml"), "ur5", "--json"]) == 2  # ur5: no gains
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert rows[-1]["status"] == "refused"


def test_configurations_random_q_and_keyframe(capsys):
    path = str(ARMS / "gen3.xml")
    assert main(["stability", path, "--random", "3", "--json"]) == 0
    assert len(json.loads(capsys.readouterr().out)["rows"]) == 3
    assert main(["stability", path, "--keyframe", "retract", "--json"]) == 0
    row = json.loads(capsys.readouterr().out)["rows"][0]
    assert row["q"][3] == pytest.approx(-2.54818071)


def test_a_trajectory_csv_is_held_row_by_row(capsys, tmp_path):
    qs = np.array([[0.0, 0.7, 0.0, -1.2, 0.3], [0.2, 0.5, 0.1, -1.0, 0.0]])
    csv = tmp_path / "path.csv"
    csv.write_text(
        "t,j1,j2,j3,j4,j5\n"
        + "".join(f"{0.1 * k}," + ",".join(map(str, q)) + "\n" for k, q in enumerate(qs))
    )
    path = str(ARMS / "general_arm.xml")
    assert main(["stability", path, "--trajectory", str(csv), "--json"]) == 0
    rows = json.loads(capsys.readouterr().out)["rows"]
    assert [r["q"] for r in rows] == qs.tolist()
    expected = stability(path, qs)
    assert [r["max_stable_timestep_s"] for r in rows] == [r.max_stable_timestep_s for r in expected]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["ur5"], "has no actuators"),
        (["ur5", "--kp", "1", "2"], "one number or 6"),
        (["ur5", "--kp", "-1"], ">= 0"),
        (["ur5", "--kp", "100", "--kd", "nan"], "kd must be finite"),
        ([str(ARMS / "ur5e.xml"), "--integrator", "Verlet"], "one of Euler"),
        ([str(ARMS / "ur5e.xml"), "--keyframe", "nope"], "'home'"),
        ([str(ARMS / "ur5e.xml"), "--timestep", "-1"], "--timestep"),
        ([str(ARMS / "ur5e.xml"), "--q", "1", "2"], "6 values"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    assert main(["stability", *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert message in err and len(err.splitlines()) == 1


def test_library_errors_name_parameters():
    with pytest.raises(InputError, match="integrator"):
        stability("ur5", kp=1.0, integrators=["euler"])
    with pytest.raises(InputError, match="timestep_s"):
        stability("ur5", kp=1.0, timestep_s=0.0)
