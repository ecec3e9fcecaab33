"""Readings that would change M are refused with one line; every value urdfdom reads is checked.

Each case was read before without a word, or with a warning saying M was unchanged while it
changed: a decimal comma, namespaces (a namespaced ``<inertial>`` the value checks could not
see, a prefixed ``link`` made real, a document re-serialised so that urdfdom lost a mass), an
unexpanded xacro call. The controls are the clean arm of ``real_shapes`` and Pinocchio itself.
"""

from __future__ import annotations

import warnings

import numpy as np
import pinocchio as pin
import pytest
from real_shapes import arm

from gimwatch.cli import main
from gimwatch.errors import URDFError, URDFWarning
from gimwatch.model.robots import load_robot

CLEAN = arm()
FIRST_INERTIAL = '<inertial><origin rpy="0 0 0" xyz="0 0.01 0.1"/><mass value="4.0"/>'
ROBOT = '<robot name="lbr_iiwa"'


def _write(tmp_path, name: str, text: str):
    path = tmp_path / f"{name}.urdf"
    path.write_text(text, encoding="utf-8")
    return path


def _gims(model: pin.Model) -> list[np.ndarray]:
    rng = np.random.default_rng(5)
    data = model.createData()
    return [pin.crba(model, data, rng.uniform(-2.9, 2.9, model.nq)).copy() for _ in range(3)]


def test_a_decimal_comma_is_refused_naming_the_element_and_attribute(tmp_path, capsys):
    path = _write(tmp_path, "comma", CLEAN.replace('xyz="0 0 0.1575"', 'xyz="0,5 0"'))
    with pytest.raises(URDFError, match=r"joint 'joint_1': <joint><origin xyz> .*'0,5 0'.*decimal"):
        load_robot(path)
    assert main(["analyze", str(path)]) == 2
    lines = capsys.readouterr().err.strip().splitlines()
    assert len(lines) == 1 and "decimal comma" in lines[0] and str(path) in lines[0], lines


def test_commas_that_only_separate_three_numbers_are_still_read(tmp_path):
    text = CLEAN.replace('xyz="0 0 0.1575"', 'xyz="0,0,0.1575"')
    with pytest.warns(URDFWarning, match="commas read as spaces"):
        robot = load_robot(_write(tmp_path, "commas", text))
    reference = load_robot(_write(tmp_path, "clean", CLEAN))
    for M, M0 in zip(_gims(robot.model), _gims(reference.model), strict=True):
        np.testing.assert_array_equal(M, M0)


def test_a_namespaced_inertial_with_a_negative_mass_is_refused(tmp_path):
    bad = FIRST_INERTIAL.replace("<inertial>", '<inertial xmlns="http://example.org/cad"> ')
    text = CLEAN.replace(FIRST_INERTIAL, bad.replace('value="4.0"', 'value="-4.0"'))
    # the control: urdfdom reads that inertial (TinyXML knows no namespaces), mass and all
    assert pin.buildModelFromXML(text).inertias[1].mass == -4.0
    with pytest.raises(URDFError, match=r"link 'link_1': mass must be >= 0 kg, got -4\.0"):
        load_robot(_write(tmp_path, "negative", text))


def test_a_namespace_and_another_quirk_keep_every_mass(tmp_path):
    """Re-serialised for the comma quirk, the namespaced <inertial> used to become
    ``<ns0:inertial>``, which urdfdom ignores: link_1 lost its 4 kg."""
    declared = FIRST_INERTIAL.replace("<inertial>", '<inertial xmlns="http://example.org/cad">')
    text = CLEAN.replace(FIRST_INERTIAL, declared)
    text = text.replace('xyz="0 0 0.2025"', 'xyz="0, 0, 0.2025"')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        robot = load_robot(_write(tmp_path, "namespace_and_commas", text))
    assert len(caught) == 1 and "lenient" in str(caught[0].message)
    assert robot.model.inertias[1].mass == 4.0
    for M, M0 in zip(_gims(robot.model), _gims(pin.buildModelFromXML(CLEAN)), strict=True):
        np.testing.assert_allclose(M, M0, rtol=0, atol=1e-14 * np.abs(M0).max())


@pytest.mark.parametrize("default_namespace", [False, True])
def test_a_prefixed_urdf_element_is_refused(tmp_path, default_namespace):
    """``<gz:link>`` is no link to urdfdom; stripping namespaces made it a real one."""
    xmlns = ' xmlns="http://www.ros.org"' if default_namespace else ""
    text = CLEAN.replace(ROBOT, f'{ROBOT}{xmlns} xmlns:gz="http://gazebosim.org/schema"')
    ghost = '<gz:link name="ghost"><inertial><mass value="9"/><inertia ixx="1" ixy="0" '
    ghost += 'ixz="0" iyy="1" iyz="0" izz="1"/></inertial></gz:link>'
    text = text.replace('<link name="flange"/>', '<link name="flange"/>' + ghost)
    text = text.replace(
        "</robot>",
        '<joint name="g" type="revolute"><parent link="flange"/>'
        '<child link="ghost"/><axis xyz="0 0 1"/><limit effort="1" lower="-1" '
        'upper="1" velocity="1"/></joint></robot>',
    )
    with pytest.raises(URDFError, match="<gz:link> in <robot> is a URDF element with a namespace"):
        load_robot(_write(tmp_path, "prefixed_link", text))


@pytest.mark.parametrize("prefix", ["xacro", "x"])
def test_an_unexpanded_xacro_macro_call_is_refused(tmp_path, prefix, capsys):
    declared = f' xmlns:{prefix}="http://www.ros.org/wiki/xacro"' if prefix != "xacro" else ""
    text = CLEAN.replace(ROBOT, ROBOT + declared)
    call = f'<{prefix}:gripper parent="flange" mass="0.8"/>'
    path = _write(tmp_path, "xacro_call", text.replace("</robot>", call + "</robot>"))
    with pytest.raises(URDFError, match=f"<{prefix}:gripper> is an unexpanded xacro .* run xacro"):
        load_robot(path)
    assert main(["analyze", str(path)]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


def test_a_bad_inertia_enters_m_unless_welded_to_a_fixed_root(tmp_path):
    """The welded base's inertia never enters M; on a free base, or on a moving link, it does."""
    path = _write(tmp_path, "welded", arm(welded_bad_inertia=True))
    with pytest.warns(URDFWarning, match="welded to the fixed root removed.*base: inertia"):
        fixed = load_robot(path)
    assert fixed.nv == 7
    with pytest.raises(URDFError, match="link 'base': inertia is not positive semi-definite"):
        load_robot(path, floating=True)
    moving = CLEAN.replace(
        'ixx="0.05" ixy="0" ixz="0" iyy="0.018"', 'ixx="-0.05" ixy="0" ixz="0" iyy="0.018"'
    )
    assert moving != CLEAN
    with pytest.raises(URDFError, match="link 'link_2': inertia is not positive semi-definite"):
        load_robot(_write(tmp_path, "moving", moving))


def test_whitespace_in_numbers_no_longer_zeroes_an_inertia(tmp_path):
    """Pinocchio alone drops link_4's inertial (urdfdom cannot read ``"\\n 0.03\\n"``)."""
    text = arm(multiline_numbers=True)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # urdfdom's complaint goes to stderr
        raw = pin.buildModelFromXML(text)
    assert raw.inertias[4].mass == 0.0  # the control: the inertia silently zeroed
    with pytest.warns(URDFWarning, match="line breaks, tabs or padding inside numbers"):
        robot = load_robot(_write(tmp_path, "multiline", text))
    assert robot.model.inertias[4].mass == 2.7
