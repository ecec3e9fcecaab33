"""Data out of the library: DataFrames, compact reprs, the summary's α, rcond, small sweeps."""

import csv
import io
import json

import numpy as np
import pytest

import gimwatch as gw
from gimwatch.cli import main
from gimwatch.survey import sweep

pandas = pytest.importorskip("pandas")  # the `pandas` extra; `make test` installs it


def _scene(metrics, **extra):
    table = {
        "robot": "chain:3",
        "duration": 0.3,
        "sample": 0.05,
        "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
        "watch": {"metrics": list(metrics)},
        **extra,
    }
    return gw.parse_scene(table, source="t.toml")


def test_trajectory_dataframe_matches_the_results_folder(tmp_path):
    trajectory = gw.run_scene(_scene(["kappa", "diagonal_ratio", "eigenvalues"]))
    frame = trajectory.to_dataframe()
    folder = gw.write_simulation(trajectory, tmp_path / "run")
    rows = list(csv.DictReader(io.StringIO((folder / "trajectory.csv").read_text())))
    assert len(frame) == len(rows) == trajectory.t.size
    for column in rows[0]:  # the CSV's columns, same names, same numbers
        np.testing.assert_array_equal(frame[column], [float(r[column]) for r in rows])
    np.testing.assert_array_equal(frame["kappa"], trajectory.watch["watch_kappa"])
    np.testing.assert_array_equal(
        frame["eigenvalues:2"], trajectory.watch["watch_eigenvalues"][:, 2]
    )
    np.testing.assert_array_equal(frame["energy"], trajectory.energy)


def test_survey_dataframe_has_one_row_per_sample():
    survey = gw.run_survey(["ur5", "chain:3"], samples=4, seed=0, workers=1)
    frame = survey.to_dataframe()
    assert len(frame) == 2 * 5 and list(frame["sample"][:5]) == [0, 1, 2, 3, 4]
    ur5 = survey.robots[0]
    np.testing.assert_array_equal(frame["kappa"][:5], ur5.metrics["kappa"])
    assert set(frame["min_diagonal_dof"][:5]) == {"wrist_3_joint"}  # names, not indices
    # κ from the frame is the analysis of the same configuration
    q0 = gw.neutral_configuration(gw.load_robot("ur5"))
    assert frame["kappa"][0] == pytest.approx(
        gw.analyze_configuration(gw.load_robot("ur5"), q0).kappa, rel=1e-12
    )


def test_robot_repr_is_one_short_line():
    text = repr(gw.load_robot("chain:4"))
    assert text.startswith("Robot(name='chain_4', spec='chain:4', nq=4, nv=4, base='fixed'")
    assert "\n" not in text and len(text) < 200 and "<robot" not in text


def test_summary_alpha_is_the_estimator_quality_alpha(tmp_path):
    trajectory = gw.run_scene(_scene(["kappa", "diagonal_ratio"]))
    summary = gw.summarize(trajectory)
    kappa, delta = trajectory.watch["watch_kappa"], trajectory.watch["watch_diagonal_ratio"]
    assert summary["alpha"] == summary["estimator_quality"]["alpha"]
    assert summary["alpha"] == pytest.approx(kappa[0] / delta[0], rel=1e-12)
    watched = gw.summarize(gw.run_scene(_scene(["kappa", "scaled_diagonal_ratio"])))
    assert watched["alpha"] == pytest.approx(watched["estimator_quality"]["alpha"], rel=1e-12)


def test_simulate_prints_the_smallest_rcond(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    scene.write_text(
        'robot = "chain:3"\nduration = 0.3\nsample = 0.05\n'
        "[effects.gravity]\nvector = [0.0, -9.81, 0.0]\n"
        '[watch]\nmetrics = ["rcond", "kappa"]\n'
    )
    assert main(["simulate", str(scene), "-o", str(tmp_path / "out")]) == 0
    out = capsys.readouterr().out
    assert "max rcond" not in out
    (line,) = [line for line in out.splitlines() if line.startswith("min rcond: ")]
    rcond = np.loadtxt(tmp_path / "out" / "watch.csv", delimiter=",", skiprows=1)[:, 1]
    header = (tmp_path / "out" / "watch.csv").read_text().splitlines()[0].split(",")
    assert header[1] == "rcond"
    assert float(line.split(": ")[1]) == pytest.approx(rcond.min(), rel=1e-5)
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["watched"][0] == "rcond"


def test_small_sweeps_run_in_this_process(monkeypatch):
    calls = []
    monkeypatch.setattr(sweep, "_run_processes", lambda *a: calls.append("pool"))
    tasks = [sweep.Task(abs, (-k,), cost_s=0.01) for k in range(5)]
    assert sweep.run_sweep(tasks).results == {k: k for k in range(5)} and calls == []
    unknown = [sweep.Task(abs, (-1,))]  # no cost stated: the pool, as before
    sweep.run_sweep(unknown)
    big = [sweep.Task(abs, (-1,), cost_s=sweep.POOL_WORTH_S)]
    sweep.run_sweep(big)
    assert calls == ["pool", "pool"] or sweep.os.cpu_count() == 1
