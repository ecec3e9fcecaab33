"""IllConditionedWarning: raised by analyze when κ·eps reaches the documented threshold."""

from __future__ import annotations

import subprocess
import sys
import warnings

import numpy as np
import pytest

from gimwatch.errors import IllConditionedWarning
from gimwatch.metrics.conditioning import ILL_CONDITIONED_KAPPA_EPS, warn_if_ill_conditioned
from gimwatch.metrics.dense_analysis import analyze_configuration
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import chain_robot

EPS = np.finfo(float).eps


def _tiny_tip_chain():
    # A 1 µm, 2.2e-12 kg tip link on two paper rods: λmin ~ m r² ~ 1e-24 kg m², κ ≫ 1/eps.
    return chain_robot(chain_spec(3, mass_kg=[2.2, 2.2, 2.2e-12], length_m=[1.0, 1.0, 1e-6]))


def test_threshold_boundary_and_exact_message():
    below = 0.99 * ILL_CONDITIONED_KAPPA_EPS / EPS
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert warn_if_ill_conditioned(below, where="r") is False
    kappa = 2.0 * ILL_CONDITIONED_KAPPA_EPS / EPS
    with pytest.warns(IllConditionedWarning) as record:
        assert warn_if_ill_conditioned(kappa, where="robot r at q0") is True
    assert str(record[0].message) == (
        f"robot r at q0: M is ill-conditioned: kappa = {kappa:.3g}, kappa*eps = 0.02 >= 0.01; "
        "results computed with M keep fewer than two significant digits"
    )


def test_analyze_warns_beyond_one_over_eps():
    robot = _tiny_tip_chain()
    with pytest.warns(IllConditionedWarning, match="ill-conditioned"):
        result = analyze_configuration(robot, np.zeros(robot.nv))
    assert result.kappa * EPS >= ILL_CONDITIONED_KAPPA_EPS


def test_analyze_of_the_paper_chain_is_quiet():
    robot = chain_robot(chain_spec(7))
    with warnings.catch_warnings():
        warnings.simplefilter("error", IllConditionedWarning)
        result = analyze_configuration(robot, np.zeros(robot.nv))
    assert result.kappa * EPS < ILL_CONDITIONED_KAPPA_EPS


def test_cli_analyze_reports_one_stderr_line(tmp_path):
    from gimwatch.model.chains import write_chain_urdf

    path = write_chain_urdf(
        chain_spec(3, mass_kg=[2.2, 2.2, 2.2e-12], length_m=[1.0, 1.0, 1e-6]), tmp_path / "tip.urdf"
    )
    run = subprocess.run(
        [sys.executable, "-m", "gimwatch", "analyze", str(path), "--q", "0", "0", "0"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert run.returncode == 0, run.stderr
    lines = [line for line in run.stderr.splitlines() if "ill-conditioned" in line]
    assert len(lines) == 1 and lines[0].startswith("gimwatch: warning: "), run.stderr
    assert "Traceback" not in run.stderr and "warnings.warn" not in run.stderr


def _ill_chain_urdf(tmp_path):
    """A 1 mm, 22 µg tip on two paper rods: κ ≈ 2e14–4e14, κ·eps ≥ 0.05 but M still regular
    (λmin well above nv·eps·λmax, so crosscheck compares q̈ instead of calling M singular)."""
    from gimwatch.model.chains import write_chain_urdf

    spec = chain_spec(3, mass_kg=[2.2, 2.2, 2.2e-8], length_m=[1.0, 1.0, 1e-3])
    return write_chain_urdf(spec, tmp_path / "ill.urdf")


def test_crosscheck_warns_once_with_the_largest_kappa(tmp_path):
    from gimwatch.crosscheck import crosscheck_robot
    from gimwatch.model.robots import load_robot

    robot = load_robot(str(_ill_chain_urdf(tmp_path)))
    with pytest.warns(IllConditionedWarning) as record:
        result = crosscheck_robot(robot, samples=3, seed=0)
    ill = [w for w in record if issubclass(w.category, IllConditionedWarning)]
    assert len(ill) == 1 and "largest over 3 samples" in str(ill[0].message)
    assert result.kappa_max * EPS >= ILL_CONDITIONED_KAPPA_EPS and "singular" not in result.note


def test_survey_warns_per_ill_conditioned_robot_and_not_for_others(tmp_path):
    from gimwatch.survey.run import run_survey

    path = str(_ill_chain_urdf(tmp_path))
    with pytest.warns(IllConditionedWarning) as record:
        result = run_survey([path, "chain:4"], samples=5, seed=0)
    ill = [str(w.message) for w in record if issubclass(w.category, IllConditionedWarning)]
    assert len(ill) == 1 and ill[0].startswith("ill (largest over its samples): ")
    assert max(r.quantiles["kappa"]["max"] for r in result.robots) * EPS >= 1e-2


@pytest.mark.parametrize("command", ["crosscheck", "survey"])
def test_cli_crosscheck_and_survey_print_one_warning_line(command, tmp_path):
    path = str(_ill_chain_urdf(tmp_path))
    argv = [command, path] + (
        ["--samples", "3", "-o", str(tmp_path / "out")] if command == "survey" else []
    )
    run = subprocess.run(
        [sys.executable, "-m", "gimwatch", *argv], capture_output=True, text=True, timeout=300
    )
    warning_lines = [line for line in run.stderr.splitlines() if "ill-conditioned" in line]
    assert len(warning_lines) == 1 and warning_lines[0].startswith("gimwatch: warning: "), (
        run.stderr
    )
