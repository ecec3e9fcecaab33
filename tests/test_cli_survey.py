import csv
import json

import numpy as np
import pytest

import gimwatch.survey
from gimwatch.cli import main


def run(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_survey_writes_report_json_csv_and_plots(capsys, tmp_path):
    argv = ["survey", "chain:4", "ur5", "cassie", "--samples", "6", "--workers", "1"]
    code, out, err = run(capsys, *argv, "-o", str(tmp_path))
    assert code == 0, err
    assert "not surveyed: cassie: robot 'cassie'" in out and "chain_4" in out
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
    real = gimwatch.survey._survey_chunk

    def interrupted_after_one_chunk(*args):
        calls.append(1)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(*args)

    monkeypatch.setattr(gimwatch.survey, "_survey_chunk", interrupted_after_one_chunk)
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
    ],
)
def test_survey_bad_arguments(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2 and err.count("\n") == 1 and message in err and out == ""
