"""Hostile MJCF inputs: budgets checked before MuJoCo runs, MuJoCo's refusals in one line."""

from __future__ import annotations

import numpy as np
import pytest

from gimwatch.cli import main
from gimwatch.errors import InputError, URDFError
from gimwatch.model.mjcf_robot import MAX_BODY_DEPTH
from gimwatch.model.robots import load_robot

pytest.importorskip("mujoco")

_BODY = '<body name="b{i}" pos="0 0 .1"><joint name="j{i}" axis="0 1 0"/><geom size=".01"/>'


def _nested(n: int) -> str:
    bodies = "".join(_BODY.format(i=i) for i in range(n))
    return f"<mujoco><worldbody>{bodies}{'</body>' * n}</worldbody></mujoco>"


def _side_by_side(n: int) -> str:
    bodies = "".join(_BODY.format(i=i) + "</body>" for i in range(n))
    return f"<mujoco><worldbody>{bodies}</worldbody></mujoco>"


def test_nesting_deeper_than_the_budget_is_refused_before_mujoco(tmp_path, monkeypatch):
    import mujoco

    def never(*args, **kwargs):  # the budget must stop the file before MuJoCo runs
        raise AssertionError("MuJoCo ran")

    path = tmp_path / "deep.xml"
    path.write_text(_nested(1000))
    monkeypatch.setattr(mujoco.MjSpec, "from_file", never)
    with pytest.raises(URDFError, match=f"nests <body> more than {MAX_BODY_DEPTH} levels deep"):
        load_robot(path)


def test_nesting_within_the_budget_loads(tmp_path):
    path = tmp_path / "deep.xml"
    path.write_text(_nested(MAX_BODY_DEPTH))
    assert load_robot(path).nv == MAX_BODY_DEPTH


def test_more_bodies_than_the_budget_are_refused_and_the_variable_raises_it(
    tmp_path, monkeypatch, capsys
):
    path = tmp_path / "wide.xml"
    path.write_text(_side_by_side(30))
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "20")
    assert main(["analyze", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "has more than 20 <body> elements" in err and str(path) in err
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "30")
    assert load_robot(path).nv == 30


def test_bodies_in_included_files_count(tmp_path, monkeypatch):
    (tmp_path / "part.xml").write_text(
        "<mujoco>" + "".join(_BODY.format(i=i) + "</body>" for i in range(30)) + "</mujoco>"
    )
    path = tmp_path / "main.xml"
    path.write_text('<mujoco><worldbody><include file="part.xml"/></worldbody></mujoco>')
    assert load_robot(path).nv == 30
    monkeypatch.setenv("GIMWATCH_MAX_LINKS", "20")
    with pytest.raises(URDFError, match="has more than 20 <body> elements"):
        load_robot(path)


def test_a_file_larger_than_the_budget_is_refused_unread(tmp_path):
    from gimwatch.model.mjcf_robot import MAX_MJCF_BYTES

    path = tmp_path / "big.xml"
    with path.open("w") as handle:
        handle.write("<mujoco>")
        handle.truncate(MAX_MJCF_BYTES + 1)  # sparse: no disk used
    with pytest.raises(URDFError, match="bytes"):
        load_robot(path)


def test_a_utf8_byte_order_mark_is_read(tmp_path):
    path = tmp_path / "bom.xml"
    text = '<mujoco><worldbody><body name="b"><joint name="j"/><geom size=".1" pos=".2 0 0"/>'
    path.write_bytes(b"\xef\xbb\xbf" + (text + "</body></worldbody></mujoco>").encode())
    robot = load_robot(path)
    assert robot.joint_names == ("j",)


def test_body_selects_a_subtree_and_an_unknown_body_is_named(tmp_path):
    path = tmp_path / "two.xml"
    path.write_text(_side_by_side(2))
    assert load_robot(path, body="b1").joint_names == ("j1",)
    with pytest.raises(InputError, match=r"^body must be the name of a body of .*, got 'arm'"):
        load_robot(path, body="arm")
    with pytest.raises(InputError, match=r"^body must be given only with an MJCF file"):
        load_robot("chain:3", body="b1")


def test_no_mujoco_warning_leaks_or_log_file_is_written(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    path = tmp_path / "nan.xml"
    path.write_text(
        '<mujoco><worldbody><body><joint/><geom size="nan"/></body></worldbody></mujoco>'
    )
    assert main(["analyze", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "nan size in geom" in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nan.xml"]


def test_armature_false_and_true_differ_by_the_armature(tmp_path):
    path = tmp_path / "arm.xml"
    path.write_text(_side_by_side(2).replace('axis="0 1 0"', 'axis="0 1 0" armature="0.5"'))
    q = np.zeros(2)
    from gimwatch.model.inertia import gim

    with_armature = gim(load_robot(path), q)
    without = gim(load_robot(path, armature=False), q)
    np.testing.assert_allclose(with_armature - without, 0.5 * np.eye(2), atol=1e-15)


def test_without_mujoco_an_mjcf_file_is_one_line_saying_what_to_install(
    tmp_path, monkeypatch, capsys
):
    import sys

    path = tmp_path / "m.xml"
    path.write_text(_side_by_side(1))
    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    assert main(["analyze", str(path)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "pip install 'gimwatch[mjcf]'" in err


def test_without_mujoco_every_entry_point_gives_the_one_install_hint(monkeypatch):
    import sys

    from gimwatch.model.mjcf_compiled import MUJOCO_INSTALL
    from gimwatch.watch.sources import MujocoSource

    monkeypatch.setitem(sys.modules, "mujoco", None)  # import mujoco raises ImportError
    with pytest.raises(InputError, match=r"^a MuJoCo watch must be MuJoCo installed") as caught:
        MujocoSource(object(), object())
    assert MUJOCO_INSTALL in str(caught.value)
