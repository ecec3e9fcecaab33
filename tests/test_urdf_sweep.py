"""The URDF sweep (benchmarks/urdf_sweep.py) on a small copied set of real-world quirk shapes.

tests/data/real_quirks holds small stripped files written here in the shapes the sweep of
public collections met: Unitree H1-2's unnamed visual materials, pybullet's racecar's
duplicate materials, Unitree's hands' numbers wrapped over lines, cuRobo's panda's non-PSD
inertia welded to the world; and two that must be refused (a decimal comma, an unexpanded
xacro call). The lenient ones give MuJoCo's M (its own URDF import, 1e-12) with one warning.
"""

from __future__ import annotations

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
QUIRKS = ROOT / "tests" / "data" / "real_quirks"
_spec = importlib.util.spec_from_file_location("urdf_sweep", ROOT / "benchmarks" / "urdf_sweep.py")
sweep = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(sweep)

LENIENT = {
    "h1_2_unnamed_material.urdf": "raw",
    "racecar_duplicate_material.urdf": "raw",
    "dex_hand_multiline_numbers.urdf": "raw",
    "curobo_panda_welded_inertia.urdf": "normalised",  # MuJoCo refuses the raw inertia
}
REFUSED = {
    "decimal_comma.urdf": "decimal comma in a number: write a decimal point",
    "xacro_call.urdf": "unexpanded xacro: run xacro first",
}


def test_the_copied_set_is_what_the_test_covers():
    assert sorted(p.name for p in QUIRKS.glob("*.urdf")) == sorted({**LENIENT, **REFUSED})


@pytest.mark.parametrize("name", sorted(LENIENT))
def test_a_lenient_quirk_gives_mujocos_m_with_one_warning(name):
    row = sweep.sweep_one(QUIRKS / name)
    assert row["outcome"] == "exact", row
    assert float(row["mujoco_rel_err"]) <= 1e-12 and row["warnings"] == 1, row
    assert row["mujoco_input"] == LENIENT[name], row


@pytest.mark.parametrize("name", sorted(set(LENIENT) - {"curobo_panda_welded_inertia.urdf"}))
def test_pinocchio_alone_refuses_or_complains_about_the_raw_file(name):
    """The control: urdfdom prints an error (and drops or refuses) on each raw file."""
    code = f"import pinocchio; pinocchio.buildModelFromXML(open({str(QUIRKS / name)!r}).read())"
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=False)
    assert done.returncode != 0 or "Error" in done.stderr, name


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_a_quirk_that_would_change_m_is_refused_with_an_actionable_class(name):
    row = sweep.sweep_one(QUIRKS / name)
    assert row["outcome"] == "refused" and row["reason"] == REFUSED[name], row


def test_every_reason_class_is_one_a_user_can_act_on():
    assert all(":" in kind for _, kind in sweep.REASONS)  # each says what to do
    assert sweep.reason_class("something unforeseen") == "other"


@pytest.mark.parametrize("name", sorted(LENIENT))
def test_denoc_reads_the_lenient_files_as_pinocchio_does(name):
    # the independent DeNOC reader applies the same lenient readings (a welded invalid
    # inertia on a fixed base included), so its M equals Pinocchio's at a random q
    import warnings

    import numpy as np

    from gimwatch.metrics.denoc_robot import denoc_model
    from gimwatch.model.inertia import gim
    from gimwatch.model.robots import load_robot
    from gimwatch.model.sampling import random_configurations

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_robot(str(QUIRKS / name))
        model = denoc_model(robot)
    q = random_configurations(robot, 1, seed=2)[0]
    M = gim(robot, q)
    assert np.abs(model.gim(q) - M).max() <= 1e-12 * np.abs(M).max()
