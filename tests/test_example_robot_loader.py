"""Every example-robot-data name against ``example_robot_data.load``, an independent loader.

gimwatch reads each robot's URDF as written (fixed base unless asked otherwise); the loader
may add a free-flyer, lock joints or add rotor inertias from the SRDF. With the base chosen as
the loader chooses it, the two mass matrices must agree at the neutral configuration, or the
name must carry a note (``EXAMPLE_ROBOT_NOTES``) that ``load_robot`` issues as one warning.
"""

from __future__ import annotations

import contextlib
import io
import warnings

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.errors import ExampleRobotWarning, GimwatchError
from gimwatch.model.example_robots import EXAMPLE_ROBOT_NOTES, example_robot_names
from gimwatch.model.robot_spec import default_floating
from gimwatch.model.robots import load_robot

example_robot_data = pytest.importorskip("example_robot_data")


def _loader_model(name: str) -> pin.Model | None:
    try:
        with contextlib.redirect_stdout(io.StringIO()):
            return example_robot_data.load(name).model
    except ImportError:  # SDF-only robots need a Pinocchio built with SDFormat
        return None


def _agrees(name: str) -> bool:
    """Whether gimwatch's model of ``name`` has the loader's M(q0): its default base included."""
    reference = _loader_model(name)
    if reference is None:
        return True  # nothing to compare with; gimwatch refuses SDF-only robots itself
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            robot = load_robot(name)  # no base asked: it must be the loader's
        except GimwatchError:
            return True  # refusals are tested with the bad-input corpus
    if robot.nv != reference.nv or robot.nq != reference.nq:
        return False
    expected = pin.crba(reference, reference.createData(), pin.neutral(reference))
    got = pin.crba(robot.model, robot.model.createData(), pin.neutral(robot.model))
    return bool(np.allclose(got, expected, rtol=0, atol=1e-12 * np.max(np.abs(expected))))


@pytest.mark.slow
def test_every_name_matches_the_loader_or_is_noted():
    differing = [name for name in example_robot_names() if not _agrees(name)]
    assert differing, "expected the talos family to differ (rotor inertias from the SRDF)"
    unnoted = sorted(set(differing) - set(EXAMPLE_ROBOT_NOTES))
    assert not unnoted, f"differ from example_robot_data.load without a note: {unnoted}"


@pytest.mark.parametrize("name", ["talos_arm", "ur3"])
def test_noted_names_warn_once_in_one_line(name):
    with pytest.warns(ExampleRobotWarning) as record:
        load_robot(name)
    notes = [w for w in record if issubclass(w.category, ExampleRobotWarning)]
    assert len(notes) == 1
    message = str(notes[0].message)
    assert message.startswith(f"{name}: ") and "\n" not in message


def test_talos_arm_differs_by_the_loaders_armature_only():
    """The loader's M minus its armature is gimwatch's M: the note's explanation holds."""
    reference = _loader_model("talos_arm")
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ExampleRobotWarning)
        robot = load_robot("talos_arm")
    assert np.any(reference.armature > 0)
    expected = pin.crba(reference, reference.createData(), pin.neutral(reference))
    got = pin.crba(robot.model, robot.model.createData(), pin.neutral(robot.model))
    np.testing.assert_allclose(got + np.diag(reference.armature), expected, rtol=1e-12, atol=0)


@pytest.mark.parametrize("name", ["anymal", "solo12", "iris", "ur5", "panda"])
def test_the_default_base_is_the_loaders(name):
    reference = _loader_model(name)
    free_flyer = reference.joints[1].shortname() == "JointModelFreeFlyer"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        robot = load_robot(name)
        fixed = load_robot(name, floating=False) if free_flyer and name != "iris" else robot
    assert (robot.floating, robot.nq, robot.nv) == (free_flyer, reference.nq, reference.nv)
    assert default_floating(name) is free_flyer
    if free_flyer and name != "iris":  # a drone has no joint on a fixed base
        assert (fixed.floating, fixed.nv) == (False, reference.nv - 6)


def test_commands_agree_on_the_default_base(capsys):
    from gimwatch.cli import main
    from gimwatch.cli.robots import robot_rows

    rows = {r["name"]: r for r in robot_rows()}
    assert (rows["anymal"]["base"], rows["anymal"]["nv"]) == ("floating", 18)
    assert (rows["ur5"]["base"], rows["ur5"]["nv"]) == ("fixed", 6)
    capsys.readouterr()
    assert main(["analyze", "anymal", "--json"]) == 0
    assert '"base": "floating"' in capsys.readouterr().out
    assert main(["analyze", "anymal", "--fixed"]) == 0
    assert capsys.readouterr().out.startswith("anymal: nv = 12, fixed base")
    assert main(["analyze", "ur5", "--floating"]) == 0
    assert capsys.readouterr().out.startswith("ur5: nv = 12, floating base")
    assert load_robot("chain:3").floating is False  # chains and files: fixed


def test_a_scene_without_base_gets_the_robots_default():
    from gimwatch.simulation.scene import parse_scene
    from gimwatch.simulation.scene_robot import load_scene_robot

    def base(**extra):
        table = {"robot": "solo12", "duration": 0.1, "sample": 0.05, **extra}
        return load_scene_robot(parse_scene(table)).floating

    assert base() is True and base(base="fixed") is False and base(base="floating") is True
    chain = parse_scene({"robot": "chain:3", "duration": 0.1, "sample": 0.05})
    assert load_scene_robot(chain).floating is False
