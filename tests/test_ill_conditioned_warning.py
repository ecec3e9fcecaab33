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
