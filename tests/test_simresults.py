import json
import shutil
from pathlib import Path

import numpy as np
import pytest

from gimwatch.cli import main
from gimwatch.output.folders import write_marker

SCENES = Path(__file__).resolve().parents[1] / "gimwatch" / "scenes"


def test_simulate_command_writes_a_complete_results_folder(tmp_path, capsys):
    out = tmp_path / "run"
    code = main(["simulate", str(SCENES / "chain_4.toml"), "-o", str(out)])
    stdout, stderr = capsys.readouterr()
    assert code == 0, stderr
    assert "chain_4: completed, t = 5 s" in stdout
    names = {p.name for p in out.iterdir()}
    assert {
        "trajectory.npz",
        "trajectory.csv",
        "watch.csv",
        "summary.json",
        "joints.png",
        "energy.png",
        "kappa_delta.png",
        "kappa_scaled.png",
        "pivot_ratios.png",
        "eigenvalues.png",
        "diagonal.png",
    } <= names
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["steps"] > 0
    assert summary["rhs_evaluations"] > summary["steps"]
    assert summary["energy_drift_relative"] < 1e-8
    assert summary["versions"]["pinocchio"] and summary["scene"]["robot"] == "chain:4"
    arrays = np.load(out / "trajectory.npz", allow_pickle=False)
    assert arrays["q"].shape == (501, 4) and arrays["watch_eigenvalues"].shape == (501, 4)
    # estimator quality recomputed independently from the saved series
    kappa, delta = arrays["watch_kappa"], arrays["watch_diagonal_ratio"]
    quality = summary["estimator_quality"]
    alpha = kappa[0] / delta[0]
    assert quality["alpha"] == pytest.approx(alpha) == summary["alpha"]
    errors = (np.abs(alpha * delta - kappa) / kappa)[1:]  # after t0, where αδ = κ by construction
    assert quality["max_relative_error"] == pytest.approx(errors.max())
    assert quality["median_relative_error"] == pytest.approx(np.median(errors))
    assert quality["pearson_log"] == pytest.approx(np.corrcoef(np.log(delta), np.log(kappa))[0, 1])
    csv = (out / "watch.csv").read_text().splitlines()
    assert (
        csv[0]
        == "t,kappa,diagonal_ratio,scaled_diagonal_ratio,pivot_ratio_forward,pivot_ratio_backward"
    )
    assert len(csv) == 502
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


@pytest.mark.parametrize("scene", ["ur5_falling.toml", "panda_pd.toml"])
def test_example_robot_scenes_run(tmp_path, capsys, scene):
    out = tmp_path / "run"
    code = main(["simulate", str(SCENES / scene), "-o", str(out)])
    _, stderr = capsys.readouterr()
    assert code == 0, stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["energy_drift_relative"] is None


def test_panda_pd_reaches_its_target(tmp_path, capsys):
    main(["simulate", str(SCENES / "panda_pd.toml"), "-o", str(tmp_path / "run")])
    arrays = np.load(tmp_path / "run" / "trajectory.npz")
    target = np.zeros(9)
    target[[0, 1, 3, 5, 6, 7, 8]] = [0.5, -0.4, -2.0, 1.6, 0.8, 0.02, 0.02]
    np.testing.assert_allclose(arrays["q"][-1], target, atol=0.05)


def test_a_diverging_run_keeps_its_results_and_exits_1(tmp_path, capsys):
    scene = tmp_path / "stiff.toml"
    scene.write_text(
        'robot = "chain:1"\nduration = 100.0\nsample = 1.0\nq = 0.1\n'
        "[effects.spring]\nstiffness = 1e6\n"
        '[integrator]\nmethod = "semi-implicit-euler"\ndt = 0.5\n'
    )
    out = tmp_path / "run"
    code = main(["simulate", str(scene), "-o", str(out)])
    _, stderr = capsys.readouterr()
    assert code == 1
    assert "gimwatch: error: non-finite " in stderr and "results so far were written" in stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "diverged" and 0 < summary["samples"] < 101


def test_rewriting_replaces_the_folder_whole(tmp_path, capsys):
    scene = tmp_path / "s.toml"
    shutil.copy(SCENES / "ur5_falling.toml", scene)
    out = tmp_path / "run"
    out.mkdir()
    (out / "stale.png").write_text("old")  # a file an earlier run wrote (its marker says so)
    write_marker(out, "simulate")
    assert main(["simulate", str(scene), "-o", str(out)]) == 0
    assert not (out / "stale.png").exists() and (out / "summary.json").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run", "s.toml"]
