"""`gimwatch explain`, `map`, `armature` and `analyze --explain` through main([...])."""

from __future__ import annotations

import json

import numpy as np
import pinocchio as pin
import pytest
from conftest import planar_rod_chain_gim

from gimwatch.cli import main
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations


def test_explain_prints_modes_and_ranked_sensitivities(capsys):
    assert main(["explain", "ur5", "--q", "0.3", "-0.7", "1.1", "0.2", "-0.4", "0.9"]) == 0
    out = capsys.readouterr().out
    assert "lambda_min = " in out and "moves wrist_3_joint" in out
    assert "wrist_3_link+ee_link+tool0  Iyy" in out  # the top elasticity at that q


def test_explain_json_holds_every_parameter(capsys):
    assert main(["explain", "chain:3", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    values = np.linalg.eigvalsh(planar_rod_chain_gim(np.zeros(3), 2.2, 1.0))  # closed form
    assert record["sensitivities"]["kappa"] == pytest.approx(values[-1] / values[0], rel=1e-12)
    assert len(record["sensitivities"]["sensitivities"]) == 3 * 13 + 3
    assert sum(record["modes"]["lowest"]["joints"].values()) == pytest.approx(1.0)


def test_analyze_explain_adds_modes(capsys):
    assert main(["analyze", "chain:3", "--random", "2", "--explain", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    assert all("modes" in c for c in record["configurations"])
    assert main(["analyze", "chain:3", "--explain"]) == 0
    assert "config 0: lambda_max = " in capsys.readouterr().out


def test_armature_command_prints_the_plan(capsys):
    assert main(["armature", "ur5", "--target", "60", "--samples", "5", "--json"]) == 0
    record = json.loads(capsys.readouterr().out)
    robot = load_robot("ur5")
    added = np.array([record["armature"][name] for name in robot.dof_names])
    assert record["total"] == pytest.approx(added.sum(), rel=1e-12)

    def kappa(q, armature):  # NumPy on Pinocchio's CRBA with the armature on its diagonal
        values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), q) + np.diag(armature))
        return values[-1] / values[0]

    qs = random_configurations(robot, 5, seed=0)  # the command's samples (its default seed)
    np.testing.assert_allclose(
        record["kappa_before"], [kappa(q, np.zeros(robot.nv)) for q in qs], rtol=1e-10
    )
    after = [kappa(q, added) for q in qs]
    np.testing.assert_allclose(record["kappa_after"], after, rtol=1e-10)
    assert max(after) <= 60
    # minimal: a little less armature breaks the target
    assert max(kappa(q, added * (1 - 1e-6)) for q in qs) > 60


def test_map_command_writes_the_folder(tmp_path, capsys):
    out = tmp_path / "m"
    argv = ["map", "chain:3", "--joints", "joint_2", "joint_3", "--grid", "4", "-o", str(out)]
    assert main(argv) == 0
    assert "kappa: " in capsys.readouterr().out
    assert {p.name for p in out.iterdir()} >= {"map.csv", "map.json", "map_kappa.png"}
    csv = tmp_path / "q.csv"
    csv.write_text("0,0,0\n0.1,0.2,0.3\n")
    argv = ["map", "chain:3", "--trajectory", str(csv), "-o", str(tmp_path / "t")]
    assert main(argv) == 0
    assert (tmp_path / "t" / "trajectory.png").exists()


def test_map_reads_the_trajectory_simulate_writes(tmp_path, capsys):
    """simulate → map --trajectory: the q:<joint> columns are the q, the v:<joint> ones left out."""
    assert main(["simulate", "chain_4", "-o", str(tmp_path / "sim")]) == 0
    capsys.readouterr()
    trajectory = tmp_path / "sim" / "trajectory.csv"
    assert main(["map", "chain:4", "--trajectory", str(trajectory), "-o", str(tmp_path / "m")]) == 0
    out, err = capsys.readouterr()
    assert f"wrote {tmp_path / 'm'}" in err and "wrote" not in out  # as the other commands
    table = np.genfromtxt(tmp_path / "m" / "trajectory.csv", delimiter=",", names=True)
    sim = np.genfromtxt(trajectory, delimiter=",", names=True)
    robot = load_robot("chain:4")
    for k in (0, len(sim) // 2, len(sim) - 1):  # κ of Pinocchio's M at the file's q, not its v
        q = np.array([sim[f"qjoint_{j}"][k] for j in range(1, 5)])
        eigenvalues = np.linalg.eigvalsh(pin.crba(robot.model, robot.model.createData(), q))
        np.testing.assert_allclose(table["kappa"][k], eigenvalues[-1] / eigenvalues[0], rtol=1e-9)


def test_map_trajectory_names_a_missing_q_column(tmp_path, capsys):
    path = tmp_path / "t.csv"
    path.write_text("t,q:joint_1,q:joint_2,v:joint_1\n0,0,0,0\n")
    assert main(["map", "chain:3", "--trajectory", str(path), "-o", str(tmp_path / "m")]) == 2
    assert "q:<name> columns joint_1, joint_2, joint_3" in capsys.readouterr().err


def test_armature_table_has_units_and_says_none_where_no_armature_is_needed(capsys):
    assert main(["armature", "ur5", "--target", "100", "--samples", "5", "--per-joint"]) == 0
    lines = capsys.readouterr().out.splitlines()
    header = next(line for line in lines if line.startswith("coordinate"))
    assert header.split() == ["coordinate", "armature", "unit"]
    assert (
        main(["armature", "ur5", "--target", "100", "--samples", "5", "--per-joint", "--json"]) == 0
    )
    added = json.loads(capsys.readouterr().out)["armature"]
    rows = {line.split()[0]: line.split()[1:] for line in lines if line.split()[0] in added}
    largest = max(added.values())
    for name, value in added.items():  # the float64 lift (relative 1e-9) is no rotor to add
        shown, unit = rows[name]
        assert unit == "kg*m^2"  # every UR5 joint turns
        assert (shown == "none") == (value <= 1e-6 * largest)
    assert any(shown == "none" for shown, _ in rows.values())


@pytest.mark.parametrize(
    ("extra", "flag_message"),
    [
        (["--joints", "joint_1", "nope", "--grid", "3"], "--joints must be joints of chain_3"),
        (["--joints", "joint_1", "joint_2", "--grid", "1"], "--grid must be an integer from 2"),
        (
            ["--joints", "joint_1", "joint_2", "--grid", "3", "--range", "1", "0", "0", "1"],
            "--range must be finite lower < upper",
        ),
        (["--trajectory", "missing.csv"], "--trajectory must be a readable CSV file"),
    ],
)
def test_map_errors_name_the_flags_the_library_calls_parameters(extra, flag_message, capsys):
    # the library says joints/grid/ranges/path (its parameters); the command line its flags
    assert main(["map", "chain:3", *extra, "-o", "unused-map-folder"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"gimwatch: error: {flag_message}"), err
