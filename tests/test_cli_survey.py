import csv
import json

import numpy as np
import pytest

import gimwatch.survey.run
from gimwatch.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_survey_writes_report_json_csv_and_plots(capsys, tmp_path):
    argv = ["survey", "chain:4", "ur5", "cassie", "--samples", "6", "--workers", "1"]
    code, out, err = run(capsys, *argv, "-o", str(tmp_path))
    assert code == 2, err  # a robot named on the command line was refused: reported, status 2
    assert "refused: cassie: robot 'cassie'" in out and "chain_4" in out
    names = {p.name for p in tmp_path.iterdir()}
    assert {"report.md", "survey.json", "survey.csv", "table.md"} <= names
    for png in ("kappa_vs_delta.png", "kappa_vs_delta_per_robot.png"):
        assert (tmp_path / png).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    record = json.loads((tmp_path / "survey.json").read_text())
    assert [r["robot"] for r in record["robots"]] == ["chain_4", "ur5"]
    assert record["failures"][0]["spec"] == "cassie" and record["interrupted"] is False
    rows = list(csv.DictReader((tmp_path / "survey.csv").open()))
    assert len(rows) == 2 * 7
    chain = [r for r in rows if r["robot"] == "chain_4"]
    assert float(chain[0]["kappa"]) == pytest.approx(1074.44, abs=0.01)  # paper, Eq. (8)
    kappa = np.array([float(r["kappa"]) for r in chain])
    assert record["robots"][0]["quantiles"]["kappa"]["max"] == kappa.max()
    report = (tmp_path / "report.md").read_text()
    assert "| chain_4 | 4 | fixed |" in report and "| cassie | load |" in report
    assert (tmp_path / "table.md").read_text() in report
    # ur5: the wrist's last joint carries the smallest M_ii and lambda_min; the shoulder lambda_max
    extreme = record["robots"][1]["extreme_dofs"]
    assert extreme["lambda_min_dof"]["dof"] == "wrist_3_joint"
    assert extreme["lambda_max_dof"]["dof"] == "shoulder_lift_joint"
    header = "| robot | largest M_ii | smallest M_ii | λmax eigenvector | λmin eigenvector |"
    (row,) = [line for line in report.splitlines() if line.startswith("| ur5 | shoulder")]
    assert report.count(header) == 1
    assert row.split(" | ")[3:5] == ["shoulder_lift_joint (100%)", "wrist_3_joint (100%)"]


def test_survey_ctrl_c_writes_partial_results_and_exits_130(capsys, tmp_path, monkeypatch):
    calls = []
    real = gimwatch.survey.run._survey_chunk

    def interrupted_after_one_chunk(*args):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(gimwatch.survey.run, "_survey_chunk", interrupted_after_one_chunk)
    argv = ["survey", "ur5", "--samples", "9", "--chunk-size", "4", "--workers", "1"]
    code, _, err = run(capsys, *argv, "-o", str(tmp_path))
    assert code == 130 and "interrupted; partial results written" in err
    record = json.loads((tmp_path / "survey.json").read_text())
    assert record["interrupted"] is True and record["robots"][0]["samples"] == 4
    assert "**Interrupted**" in (tmp_path / "report.md").read_text()


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["survey", "ur5", "--samples", "0"], "argument --samples: must be a positive integer"),
        (["survey", "ur5", "--workers", "x"], "argument --workers: must be a positive integer"),
        (["survey"], "the following arguments are required: ROBOT"),
        (
            ["survey", "ur5", "--trajectory", "--duration", "0"],
            "argument --duration: must be a positive number of seconds, got '0'",
        ),
        (["survey", "ur5", "--runs", "-1"], "argument --runs: must be a positive integer"),
    ],
)
def test_survey_bad_arguments(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2 and err.count("\n") == 1 and message in err and out == ""


def test_survey_trajectory_writes_the_along_run_columns(capsys, tmp_path):
    argv = ["survey", "ur5", "hector", "--samples", "3", "--workers", "1", "--trajectory"]
    code, out, err = run(capsys, *argv, "--duration", "0.1", "--runs", "2", "-o", str(tmp_path))
    assert code == 0, err
    assert "run pearson" in out.splitlines()[0]
    rows = list(csv.DictReader((tmp_path / "survey.csv").open()))
    assert list(rows[0])[:4] == ["robot", "sample", "trajectory", "t_s"]
    samples = [r for r in rows if r["trajectory"] == ""]
    runs = [r for r in rows if r["trajectory"] != ""]
    assert len(samples) == 2 * 4 and {r["robot"] for r in runs} == {"ur5"}
    assert len(runs) == 2 * 11  # 2 runs, 0.1 s sampled every 0.01 s (duration / 10)
    record = json.loads((tmp_path / "survey.json").read_text())
    assert record["trajectory_settings"]["runs_per_robot"] == 2
    assert record["trajectory_settings"]["duration_s"] == 0.1
    ur5, hector = record["robots"]
    assert (
        hector["trajectories"]["runs"] == 0 and "floating base" in hector["trajectories"]["skipped"]
    )
    # the JSON statistics recomputed from the CSV rows (alpha = kappa/delta at t0 of each run)
    errors, pearsons = [], []
    for k in ("0", "1"):
        kappa = np.array([float(r["kappa"]) for r in runs if r["trajectory"] == k])
        delta = np.array([float(r["diagonal_ratio"]) for r in runs if r["trajectory"] == k])
        ad = np.array([float(r["scaled_diagonal_ratio"]) for r in runs if r["trajectory"] == k])
        np.testing.assert_allclose(ad, kappa[0] / delta[0] * delta, rtol=1e-12)
        errors.append(np.abs(ad[1:] - kappa[1:]) / kappa[1:])
        pearsons.append(np.corrcoef(np.log(delta), np.log(kappa))[0, 1])
    stats = ur5["trajectories"]
    assert stats["completed"] == 2
    assert stats["alpha_delta_rel_error_median"] == pytest.approx(np.median(np.concatenate(errors)))
    assert stats["pearson_log_delta_log_kappa_median"] == pytest.approx(np.median(pearsons))
    report = (tmp_path / "report.md").read_text()
    assert "## Along simulated trajectories" in report and "| ur5 | 2/2 | DOP853 |" in report
    assert "| hector | 0/0 | — |" in report
    assert "along runs: Pearson (median)" in (tmp_path / "table.md").read_text()
