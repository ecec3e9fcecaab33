"""MJCF robots and MuJoCo as an independent reference for M(q) (docs/robots.md)."""

from __future__ import annotations

import subprocess
import sys
import warnings
import xml.etree.ElementTree as ET
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.cli import main
from gimwatch.crosscheck import crosscheck_robot
from gimwatch.errors import GimwatchError, URDFError, URDFWarning
from gimwatch.model.example_robots import example_robot_names
from gimwatch.model.mujoco_model import (
    EXACT_COMPILER,
    MujocoRefusal,
    compile_robot,
    pinocchio_mass_matrix,
)
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import placeholder_limit_joints, random_configurations

mujoco = pytest.importorskip("mujoco")

MJCF = Path(__file__).parent / "data" / "mjcf"
MJCF_FILES = sorted(MJCF.glob("*.xml"))


def _crba(robot, q):
    upper = np.triu(pin.crba(robot.model, robot.model.createData(), q))
    return upper + np.triu(upper, 1).T


def test_there_are_at_least_five_mjcf_models():
    assert len(MJCF_FILES) >= 5, MJCF_FILES


@pytest.mark.parametrize("path", MJCF_FILES, ids=[p.stem for p in MJCF_FILES])
def test_mjcf_model_matches_mujoco_and_crosschecks(path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)  # panda.xml's finger equality
        robot = load_robot(str(path))
    assert robot.mjcf_xml
    mj_model = compile_robot(robot)
    for q in random_configurations(robot, 2, seed=3):
        M = _crba(robot, q)
        got = pinocchio_mass_matrix(robot, mj_model, q)
        np.testing.assert_allclose(got, M, rtol=0, atol=1e-13 * np.abs(M).max())
    result = crosscheck_robot(robot, samples=1, seed=0)
    assert result.passed, result
    # DeNOC compares too, a ball joint (slider_arm's wrist) read by its stand-ins at each q
    assert result.gim_rel_err < 1e-13 and result.qdd_rel_err is not None


@pytest.mark.parametrize("name", ["ur5", "panda", "double_pendulum", "talos_arm"])
def test_urdf_converted_to_mjcf_by_mujoco_gives_the_same_m(name, tmp_path):
    """URDF -> MuJoCo -> mj_saveLastXML -> gimwatch's MJCF reader: same M as the URDF.

    MuJoCo writes 6 significant digits, so the two models agree to about 1e-6 relative.
    """
    urdf_robot = load_robot(name)
    root = ET.fromstring(urdf_robot.urdf_xml)
    for parent in root.iter():
        for child in list(parent):
            if child.tag in ("visual", "collision"):
                parent.remove(child)
    root.insert(0, ET.fromstring(f"<mujoco><compiler {EXACT_COMPILER.format(floor=0)}/></mujoco>"))
    mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    path = tmp_path / f"{name}.xml"
    mujoco.mj_saveLastXML(
        str(path), mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    )
    mjcf_robot = load_robot(str(path))
    assert mjcf_robot.joint_names == urdf_robot.joint_names
    for q in random_configurations(urdf_robot, 3, seed=1):
        M_urdf, M_mjcf = _crba(urdf_robot, q), _crba(mjcf_robot, q)
        np.testing.assert_allclose(M_mjcf, M_urdf, rtol=0, atol=2e-5 * np.abs(M_urdf).max())


def test_floating_mjcf_adds_a_free_joint_and_matches_mujoco():
    robot = load_robot(str(MJCF / "slider_arm.xml"), floating=True)
    assert robot.nv == 12 and robot.joint_names[0] == "root_joint"
    q = random_configurations(robot, 1, seed=5)[0]
    M = _crba(robot, q)
    got = pinocchio_mass_matrix(robot, compile_robot(robot), q)
    np.testing.assert_allclose(got, M, rtol=0, atol=1e-13 * np.abs(M).max())


def test_floating_mjcf_without_a_base_body_is_refused():
    with pytest.raises(URDFError, match="its first body 'link1' already has a joint"):
        load_robot(str(MJCF / "pendulum3.xml"), floating=True)


def _erd_cases():
    return [
        pytest.param(name, floating, id=f"{name}-{'floating' if floating else 'fixed'}")
        for name in example_robot_names()
        for floating in (False, True)
    ]


@pytest.mark.parametrize(("name", "floating"), _erd_cases())
def test_every_example_robot_passes_crosscheck_with_mujoco(name, floating):
    """Pinocchio's M agrees with MuJoCo's, or MuJoCo's refusal names a link."""
    try:
        robot = load_robot(name, floating=floating)
    except GimwatchError as exc:  # the two documented refusals, and only those
        reasons = ("ships it only as SDF", "has no degree of freedom with a fixed base")
        assert any(reason in str(exc) for reason in reasons), exc
        assert floating is False or "SDF" in str(exc), exc
        return
    result = crosscheck_robot(robot, samples=1, seed=0, peer="mujoco")
    if result.mujoco_refusal:
        assert result.mujoco_refusal.startswith("MuJoCo refuses link '"), result.mujoco_refusal
        assert result.mujoco_gim_rel_err is None
    else:
        assert result.mujoco_gim_rel_err < 1e-13, result
    assert result.passed, result


def test_refusal_names_the_link():
    robot = load_robot("bravo7_gripper")
    with pytest.raises(MujocoRefusal, match="link 'bravo_finger1_link'"):
        compile_robot(robot)


def test_placeholder_limits_are_listed_and_sampled_in_range():
    robot = load_robot(str(MJCF / "slider_arm.xml"))
    assert "slide" in placeholder_limit_joints(robot)
    qs = random_configurations(robot, 50, seed=0)
    assert np.abs(qs[:, 0]).max() <= 1.0


def test_cli_crosscheck_peer_mujoco_stderr_has_only_gimwatch_lines():
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "gimwatch",
            "crosscheck",
            "double_pendulum",
            "ur5",
            str(MJCF / "pendulum3.xml"),
            "--peer",
            "mujoco",
            "--samples",
            "1",
        ],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert "M mujoco" in run.stdout
    for line in run.stderr.splitlines():
        assert line.startswith(("crosscheck:", "gimwatch:")), run.stderr


def test_talos_legs_is_flagged_because_the_loader_reduces_it():
    import example_robot_data

    loader = example_robot_data.load("talos_legs")
    robot = load_robot("talos_legs", floating=True)
    assert loader.model.nv != robot.nv  # the loader locks joints; gimwatch does not
    result = crosscheck_robot(robot, samples=1, seed=0)
    assert "example_robot_data.load locks" in result.note


@pytest.mark.parametrize("command", ["analyze", "crosscheck"])
def test_third_party_libraries_stay_quiet_on_stderr(command, tmp_path):
    """yourdfpy, urdfdom, Pinocchio's MJCF parser and MuJoCo print nothing of their own."""
    from gimwatch.model.chains import chain_spec, generate_chain_urdf

    urdf = tmp_path / "versioned.urdf"
    urdf.write_text(
        generate_chain_urdf(chain_spec(3)).replace("<robot ", '<robot version="1.1" ', 1)
    )
    for robot in (str(urdf), str(MJCF / "slider_arm.xml"), "double_pendulum"):
        extra = ["--samples", "1", "--peer", "mujoco"] if command == "crosscheck" else []
        run = subprocess.run(
            [sys.executable, "-m", "gimwatch", command, robot, *extra],
            capture_output=True,
            text=True,
            timeout=120,
        )
        assert run.returncode == 0, run.stderr
        # only gimwatch's own notes (the slider arm mixes metres and radians) may be there
        foreign = [line for line in run.stderr.splitlines() if not line.startswith("gimwatch: ")]
        assert foreign == [], run.stderr


_DOUBTFUL_INERTIA = """<mujoco model="doubtful">
  <worldbody>
    <body name="upper">
      <joint name="shoulder" type="hinge" axis="0 1 0"/>
      <inertial pos="0 0 -0.5" mass="1" diaginertia="0.1 0.1 1.0"/>
    </body>
  </worldbody>
</mujoco>
"""


def test_mjcf_inertia_violating_the_triangle_inequality_is_refused_by_mujoco(tmp_path, capsys):
    """Principal moments 0.1, 0.1, 1.0: MuJoCo's compiler refuses the body; one line, exit 2."""
    path = tmp_path / "doubtful.xml"
    path.write_text(_DOUBTFUL_INERTIA)
    assert main(["analyze", str(path), "--json"]) == 2
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and str(path) in err[0] and "'upper'" in err[0] and "A + B >= C" in err[0]


def _swing(robot: str, floating: bool = False):
    """A conservative scene: every joint at 0.5 rad (or m), gravity oblique to every axis."""
    from gimwatch.simulation.scene import parse_scene
    from gimwatch.simulation.simulate import run_scene

    scene = parse_scene(
        {
            "robot": robot,
            "base": "floating" if floating else "fixed",
            "q": 0.5,
            "duration": 0.3,
            "sample": 0.01,
            "integrator": {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10},
            "effects": {"gravity": {"vector": [0.0, -6.0, -8.0]}},
            "watch": {"metrics": ["kappa", "diagonal_ratio"]},
        }
    )
    return run_scene(scene)


@pytest.mark.parametrize(
    ("name", "floating"),
    [(p.name, False) for p in sorted(MJCF.glob("*.xml"))]
    + [(p.name, True) for p in sorted(MJCF.glob("*.xml")) if p.name != "pendulum3.xml"],
)
def test_every_mjcf_model_simulates_and_conserves_energy(name, floating):
    """Pinocchio's energy is independent of the integrator: drift <= 1e-8 at rtol = 1e-10."""
    trajectory = _swing(str(MJCF / name), floating)
    assert trajectory.status == "completed"
    moved = np.max(np.abs(trajectory.q[-1] - trajectory.q[0]))
    assert moved > 1e-3, "the scene must move the robot, else the drift proves nothing"
    assert trajectory.energy_drift() <= 1e-8
    assert np.all(trajectory.watch["watch_kappa"] >= trajectory.watch["watch_diagonal_ratio"])


def test_mjcf_ur5_swings_like_the_urdf_ur5_it_was_converted_from():
    """ur5.xml is example-robot-data's ur5 URDF converted by MuJoCo (6 significant digits)."""
    from_mjcf, from_urdf = _swing(str(MJCF / "ur5.xml")), _swing("ur5")
    assert from_mjcf.q.shape == from_urdf.q.shape
    np.testing.assert_allclose(from_mjcf.q, from_urdf.q, rtol=0, atol=5e-6)  # measured 4.5e-7
    assert np.max(np.abs(from_urdf.q[-1] - from_urdf.q[0])) > 0.05
