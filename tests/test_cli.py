import json

import numpy as np
import pinocchio as pin
import pytest
from closed_forms import rod_chain_gim
from conftest import EXAMPLE_ROBOTS, NO_DOF_WHEN_FIXED, SINGULAR_GIM

from gimwatch.cli import main
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.robots import load_robot


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_chain_command_writes_the_committed_file(capsys, tmp_path):
    out_file = tmp_path / "c.urdf"
    code, _, _ = run(capsys, "chain", "4", "-o", str(out_file))
    assert code == 0
    assert out_file.read_text() == generate_chain_urdf(chain_spec(4))
    code, out, _ = run(capsys, "chain", "3", "--mass", "1,2,3", "--axes", "spatial")
    assert code == 0 and out == generate_chain_urdf(
        chain_spec(3, mass_kg=[1, 2, 3], axes="spatial")
    )


def test_analyze_json_for_the_paper_chain(capsys):
    code, out, _ = run(capsys, "analyze", "chain:4", "--json")
    document = json.loads(out)
    assert code == 0
    assert {k: document[k] for k in ("robot", "nv", "base", "method")} == {
        "robot": "chain_4",
        "nv": 4,
        "base": "fixed",
        "method": "crba",
    }
    assert len(document["configurations"]) == 1  # a list even for one configuration
    record = document["configurations"][0]
    assert {
        "robot",
        "nv",
        "q",
        "kappa",
        "diagonal_ratio",
        "pivot_ratio_forward",
        "pivot_ratio_backward",
        "eigenvalues",
        "diagonal",
    } <= set(record)
    assert record["kappa"] == pytest.approx(1074.44, abs=0.01)
    assert record["diagonal_ratio"] == pytest.approx(64)
    assert record["max_diagonal_dof"] == "joint_1" and record["min_diagonal_dof"] == "joint_4"


def test_analyze_random_gives_a_list_and_q_is_used(capsys):
    code, out, _ = run(capsys, "analyze", "ur5", "--random", "3", "--seed", "1", "--json")
    records = json.loads(out)["configurations"]
    assert code == 0 and len(records) == 3 and [r["config"] for r in records] == [0, 1, 2]
    q = records[1]["q"]
    code, out, _ = run(capsys, "analyze", "ur5", "--json", "--q", *map(str, q))
    (record,) = json.loads(out)["configurations"]
    assert record["kappa"] == pytest.approx(records[1]["kappa"], rel=1e-12)
    # and both are κ of that q: NumPy on Pinocchio's CRBA, not the command again
    robot = load_robot("ur5")
    values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), np.array(q)))
    assert record["kappa"] == pytest.approx(values[-1] / values[0], rel=1e-10)


def test_analyze_csv_has_the_json_numbers(capsys):
    import csv
    import io

    from gimwatch.cli.analyze import CSV_COLUMNS

    _, out, _ = run(capsys, "analyze", "ur5", "--random", "2", "--seed", "1", "--json")
    records = json.loads(out)["configurations"]
    code, out, _ = run(capsys, "analyze", "ur5", "--random", "2", "--seed", "1", "--csv")
    rows = list(csv.DictReader(io.StringIO(out)))
    assert code == 0 and tuple(rows[0]) == CSV_COLUMNS and len(rows) == 2
    for row, record in zip(rows, records, strict=True):
        assert float(row["kappa"]) == record["kappa"]  # repr round-trips exactly
        assert [float(x) for x in row["q"].split(";")] == record["q"]
        assert row["min_diagonal_dof"] == record["min_diagonal_dof"]
    code, _, err = run(capsys, "analyze", "ur5", "--json", "--csv")
    assert code == 2 and "not allowed with argument" in err


@pytest.mark.parametrize("floating", [False, True], ids=["fixed", "floating"])
@pytest.mark.parametrize("name", EXAMPLE_ROBOTS)
def test_analyze_every_example_robot(capsys, name, floating):
    argv = ["analyze", name, "--json", "--floating" if floating else "--fixed"]
    code, out, err = run(capsys, *argv)
    if name in NO_DOF_WHEN_FIXED and not floating:
        assert code == 2 and err.count("\n") == 1 and "no degree of freedom" in err
        return
    if name in SINGULAR_GIM:
        assert code == 2 and err.count("\n") == 1 and "is singular" in err and "move no mass" in err
        return
    assert code == 0, err
    (record,) = json.loads(out)["configurations"]
    assert record["nv"] == len(record["diagonal"]) == len(record["eigenvalues"])
    assert np.isfinite(record["kappa"]) and record["kappa"] >= record["diagonal_ratio"] >= 1


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (
            ["chain", "0"],
            "gimwatch: error: gimwatch chain: argument n: must be a positive integer, got '0'",
        ),
        (["analyze", "ur5", "--q", "0.1"], "gimwatch: error: --q must be 6 numbers for ur5, got 1"),
        (["analyze", "ur5", "--random", "-1"], "argument --random: must be a positive integer"),
        (["analyze", "nope"], "gimwatch: error: robot 'nope': not chain:N"),
        (
            ["analyze", "ur5", "--q", "1", "--random", "2"],
            "--q and --random must be used one at a time",
        ),
        (["frobnicate"], "gimwatch: error: unknown command 'frobnicate' (commands: chain,"),
        (["analyse", "ur5"], "unknown command 'analyse'; did you mean 'analyze'?"),
    ],
)
def test_bad_arguments_give_one_line_and_exit_2(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2
    assert err.count("\n") == 1 and message in err, err
    assert out == ""


def test_demo_writes_report(capsys, tmp_path):
    code, out, _ = run(capsys, "demo", "-o", str(tmp_path), "--duration", "0.5")
    assert code == 0
    assert (tmp_path / "report.md").exists() and "| 20 |" in out
    assert not list(tmp_path.glob("*.gif"))  # the animation is opt-in (--gif)


def test_crosscheck_command_json_and_exit_codes(capsys):
    code, out, err = run(capsys, "crosscheck", "ur5", "chain:3", "--samples", "2", "--json")
    records = json.loads(out)["robots"]
    assert code == 0 and [r["robot"] for r in records] == ["ur5", "chain_3"]
    for key in ("nv", "samples", "gim_rel_err", "tau_rel_err", "qdd_rel_err", "pivots_rel_err"):
        assert key in records[0]
    assert records[0]["passed"] is True and records[0]["gim_rel_err"] < 1e-10
    assert err.splitlines() == ["crosscheck: [1/2] ur5", "crosscheck: [2/2] chain:3"]
    # agreement to round-off is not agreement to 1e-30: the check must be able to fail
    code, out, _ = run(capsys, "crosscheck", "ur5", "--samples", "2", "--tolerance", "1e-30")
    assert code == 1 and "ur5  FAIL" in out and "0/1 passed" in out
    code, _, err = run(capsys, "crosscheck", "ur5", "--tolerance", "-1")
    assert (
        code == 2 and err == "gimwatch: error: --tolerance must be a number > 0 and < 1, got -1.0\n"
    )


def test_crosscheck_all_skips_what_cannot_load_with_the_reason(capsys, monkeypatch):
    import gimwatch.cli.crosscheck as command

    monkeypatch.setattr(command, "example_robot_names", lambda: ("cassie", "iris", "romeo"))
    code, out, err = run(capsys, "crosscheck", "all", "--samples", "1", "--fixed")
    assert code == 0
    assert "crosscheck: skipped cassie: example-robot-data ships it only as SDF" in err
    assert "crosscheck: skipped iris: has no degree of freedom with a fixed base" in err
    assert "romeo: M(q) is singular" in out and "1/1 passed" in out


def test_analyze_switches_to_the_linear_path_above_the_data_limit(capsys):
    code, out, err = run(capsys, "analyze", "chain:450", "--json")
    (record,) = json.loads(out)["configurations"]
    assert code == 0 and err.count("\n") == 1 and "using the O(n) DeNOC path" in err
    assert record["method"] == "denoc-linear" and record["pivot_ratio_forward"] is None
    assert record["diagonal_ratio"] == pytest.approx(450**3, rel=1e-12)
    assert record["kappa"] / (4 * 450**4) == pytest.approx(0.975, abs=0.01)


def test_analyze_linear_path_agrees_with_crba(capsys):
    _, dense, _ = run(capsys, "analyze", "chain:30", "--json", "--random", "2", "--seed", "3")
    _, linear, _ = run(
        capsys,
        "analyze",
        "chain:30",
        "--json",
        "--random",
        "2",
        "--seed",
        "3",
        "--backend",
        "denoc",
    )
    dense_records = json.loads(dense)["configurations"]
    linear_records = json.loads(linear)["configurations"]
    for a, b in zip(dense_records, linear_records, strict=True):
        assert a["q"] == b["q"]
        # each path against NumPy on the closed-form rod chain's M, not against the other
        M = rod_chain_gim(np.array(a["q"]))
        values = np.linalg.eigvalsh(M)
        backward = np.diag(np.linalg.cholesky(M[::-1, ::-1])) ** 2
        expected = {
            "kappa": values[-1] / values[0],
            "lambda_min": values[0],
            "lambda_max": values[-1],
            "pivot_ratio_backward": backward.max() / backward.min(),
        }
        for record in (a, b):
            np.testing.assert_allclose(record["diagonal"], np.diag(M), rtol=1e-12)
            for key, value in expected.items():  # κ ≈ 1e5 here: eps·κ ≈ 2e-11
                assert record[key] == pytest.approx(value, rel=1e-8), (record["method"], key)


def test_analyze_metrics_limit_the_linear_work(capsys):
    code, out, _ = run(capsys, "analyze", "chain:500", "--json", "--metrics", "diagonal_ratio")
    (record,) = json.loads(out)["configurations"]
    assert code == 0 and record["kappa"] is None and record["pivot_ratio_backward"] is None
    assert record["diagonal_ratio"] == pytest.approx(500**3, rel=1e-12)
