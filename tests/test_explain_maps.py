"""Conditioning maps and trajectory metrics against point-by-point CRBA + eig, both paths."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
from closed_forms import rod_chain_gim

from gimwatch.errors import InputError
from gimwatch.explain.map_files import write_map, write_trajectory_metrics
from gimwatch.explain.maps import conditioning_map
from gimwatch.explain.trajectory import read_trajectory_csv, trajectory_metrics
from gimwatch.model.robots import load_robot


def _kappa_delta(robot, q):
    M = pin.crba(robot.model, robot.model.createData(), q)
    w = np.linalg.eigvalsh(M)
    d = np.diag(M)
    return w[-1] / w[0], d.max() / d.min()


def test_grid_matches_point_by_point_crba():
    robot = load_robot("ur5")
    base = np.array([0.1, -0.5, 0.7, 0.2, -0.3, 0.4])
    result = conditioning_map(
        "ur5",
        ["shoulder_lift_joint", "wrist_2_joint"],
        grid=7,
        ranges=[(-1, 1), (-2, 0.5)],
        q=base,
        metrics=["kappa", "diagonal_ratio", "pivot_ratio_forward"],
    )
    assert result.units == ("rad", "rad") and result.x[0] == -1 and result.y[-1] == 0.5
    for i in (0, 3, 6):
        for j in (0, 4, 6):
            q = base.copy()
            q[1], q[4] = result.x[j], result.y[i]
            kappa, delta = _kappa_delta(robot, q)
            assert result.values["kappa"][i, j] == pytest.approx(kappa, rel=1e-12)
            assert result.values["diagonal_ratio"][i, j] == pytest.approx(delta, rel=1e-14)
    assert np.all(result.values["pivot_ratio_forward"] >= 1)


def test_linear_path_agrees_with_the_dense_path_on_a_chain():
    dense = conditioning_map("chain:30", ["joint_05", "joint_20"], grid=4, backend="crba")
    linear = conditioning_map("chain:30", ["joint_05", "joint_20"], grid=4, backend="denoc")
    assert linear.path == "denoc" and dense.path == "crba"
    # both against NumPy on the closed-form rod chain's M at each grid point (the other
    # joints neutral, q = 0), not one path against the other
    kappa, delta = np.empty((4, 4)), np.empty((4, 4))
    for i, y in enumerate(dense.y):
        for j, x in enumerate(dense.x):
            q = np.zeros(30)
            q[4], q[19] = x, y
            M = rod_chain_gim(q)
            values, diagonal = np.linalg.eigvalsh(M), np.diag(M)
            kappa[i, j], delta[i, j] = values[-1] / values[0], diagonal.max() / diagonal.min()
    np.testing.assert_array_equal(linear.x, dense.x)
    np.testing.assert_array_equal(linear.y, dense.y)
    # κ up to 2.6e6: eps·κ ≈ 6e-10 bounds each side's λmin round-off (measured 5e-12 dense,
    # 3e-11 linear, whose Lanczos stops at its own tolerance)
    for result, rtol in ((dense, 2e-9), (linear, 1e-7)):
        np.testing.assert_allclose(result.values["kappa"], kappa, rtol=rtol, err_msg=result.path)
        np.testing.assert_allclose(result.values["diagonal_ratio"], delta, rtol=1e-12)


def test_map_runs_in_worker_processes_with_the_same_result():
    """Regression test: worker processes reproduce the serial map bit for bit (the serial
    values themselves are held against CRBA + eigvalsh in test_grid_matches_point_by_point_crba)."""
    serial = conditioning_map("chain:4", ["joint_2", "joint_3"], grid=70, metrics=["kappa"])
    pooled = conditioning_map(
        "chain:4", ["joint_2", "joint_3"], grid=70, metrics=["kappa"], workers=2
    )
    np.testing.assert_array_equal(serial.values["kappa"], pooled.values["kappa"])


def test_files_hold_the_map_and_the_trajectory(tmp_path):
    result = conditioning_map("chain:3", ["joint_2", "joint_3"], grid=5)
    write_map(result, tmp_path / "map")
    rows = np.loadtxt(tmp_path / "map" / "map.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "map" / "map.csv").read_text().splitlines()[0]
    assert header == "joint_2_rad,joint_3_rad,kappa,diagonal_ratio"
    assert rows.shape == (25, 4)
    np.testing.assert_array_equal(rows[:, 2], result.values["kappa"].ravel())
    assert (tmp_path / "map" / "map_kappa.png").stat().st_size > 1000
    csv = tmp_path / "q.csv"
    csv.write_text("t,joint_1,joint_2,joint_3\n0,0,0,0\n0.1,0.1,0.5,1.0\n")
    trajectory = trajectory_metrics("chain:3", csv)
    robot = load_robot("chain:3")
    assert trajectory.values["kappa"][1] == pytest.approx(
        _kappa_delta(robot, np.array([0.1, 0.5, 1.0]))[0], rel=1e-12
    )
    write_trajectory_metrics(trajectory, tmp_path / "traj")
    assert (tmp_path / "traj" / "trajectory.csv").read_text().startswith("t_s,kappa")


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("", "at least one row"),
        ("0,0\n", "q.csv:1 must be 3 columns, got 2"),
        ("0,0,x\n", "q.csv:1 must be numbers (column 3), got 'x'"),
        ("0,0,0\n0,nan,0\n", "q.csv:2 must be finite numbers (column 2), got 'nan'"),
        ("a,b,c\n0,0,0\n", "q.csv:1 must be column names joint_1, joint_2, joint_3"),
    ],
)
def test_bad_trajectory_files_name_the_line(tmp_path, text, message):
    path = tmp_path / "q.csv"
    path.write_text(text)
    with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
        read_trajectory_csv(path, ["joint_1", "joint_2", "joint_3"])


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"joints": ["joint_1", "nope"]}, "^joints must be joints of chain_3, got 'nope'"),
        ({"joints": ["joint_1", "joint_1"]}, "^joints must be two different joint names"),
        ({"grid": 1}, "^grid must be an integer from 2 to 2000, got 1"),
        ({"grid": 5000}, "^grid must be an integer from 2 to 2000, got 5000"),
        ({"metrics": ["eigenvalues"]}, "^metrics must be among"),
        ({"ranges": [(1, 0), (0, 1)]}, "^ranges must be finite lower < upper"),
    ],
)
def test_bad_map_arguments(kwargs, message):
    args = {"joints": ["joint_1", "joint_2"], "grid": 3} | kwargs
    joints = args.pop("joints")
    with pytest.raises(InputError, match=message.replace("(", r"\(")):
        conditioning_map("chain:3", joints, **args)
