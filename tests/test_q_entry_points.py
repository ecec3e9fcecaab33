"""Every q from every entry point meets the same checks (gimwatch.model.q_checks).

A continuous joint's (cos θ, sin θ) of norm 2 or (0, 0), and a ball joint's quaternion of
norm 2, were refused by ``analyze --q`` and the library functions but taken by
``map --trajectory`` and ``conditioning_map(q=...)``: κ wrong, or negative, and exit 0.
The reference for the accepted rows is NumPy's eigenvalues of Pinocchio's CRBA.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.cli import main
from gimwatch.errors import InputError
from gimwatch.explain.maps import conditioning_map
from gimwatch.explain.trajectory import trajectory_metrics
from gimwatch.model.robots import load_robot

_LINK = (
    '<link name="{0}"><inertial><origin xyz="0 0 0.2"/><mass value="{1}"/>'
    '<inertia ixx="0.03" ixy="0" ixz="0" iyy="0.03" iyz="0" izz="0.004"/></inertial></link>'
)
_JOINT = (
    '<joint name="{0}" type="{1}"><parent link="{2}"/><child link="{3}"/>'
    '<origin xyz="0 0 0.4"/><axis xyz="{4}"/>{5}</joint>'
)
_LIMIT = '<limit lower="-3" upper="3" effort="10" velocity="1"/>'

#: a revolute, a continuous (q = cos, sin) and a revolute joint: nq = 4, nv = 3
URDF = (
    '<robot name="wrist"><link name="base"/>'
    + _LINK.format("a", 2.0)
    + _LINK.format("b", 1.5)
    + _LINK.format("c", 1.0)
    + _JOINT.format("j1", "revolute", "base", "a", "0 1 0", _LIMIT)
    + _JOINT.format("j2", "continuous", "a", "b", "1 0 0", "")
    + _JOINT.format("j3", "revolute", "b", "c", "0 1 0", _LIMIT)
    + "</robot>"
)
#: a ball joint between two hinges: Pinocchio's q = (h1, qx, qy, qz, qw, h2)
MJCF = """<mujoco model="ball">
  <worldbody><body name="a"><joint name="h1" type="hinge" axis="0 1 0"/>
    <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.04" mass="2"/>
    <body name="b" pos="0 0 0.4"><joint name="ball" type="ball"/>
      <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.04" mass="1.5"/>
      <body name="c" pos="0 0 0.4"><joint name="h2" type="hinge" axis="0 1 0"/>
        <geom type="capsule" fromto="0 0 0 0 0 0.4" size="0.04" mass="1"/>
  </body></body></body></worldbody></mujoco>
"""

GOOD = {"urdf": [0.3, np.cos(0.7), np.sin(0.7), -0.4], "mjcf": [0.3, 0, 0, 0.6, 0.8, -0.4]}
BAD = {
    "urdf": [
        ("j2", [0.3, 2 * np.cos(0.7), 2 * np.sin(0.7), -0.4], 2.0),
        ("j2", [0.3, 0.0, 0.0, -0.4], 0.0),
    ],
    "mjcf": [("ball", [0.3, 0, 0, 1.2, 1.6, -0.4], 2.0)],
}
CASES = [(kind, joint, q, norm) for kind, bad in BAD.items() for joint, q, norm in bad]


@pytest.fixture(scope="module")
def specs(tmp_path_factory) -> dict[str, str]:
    folder = tmp_path_factory.mktemp("robots")
    (folder / "wrist.urdf").write_text(URDF, encoding="utf-8")
    (folder / "ball.xml").write_text(MJCF, encoding="utf-8")
    return {"urdf": str(folder / "wrist.urdf"), "mjcf": str(folder / "ball.xml")}


def _csv(tmp_path, spec: str, rows) -> str:
    from gimwatch.output.figures import joint_coordinate_units

    names = joint_coordinate_units(load_robot(spec).model)[0]
    path = tmp_path / "trajectory.csv"
    lines = [",".join(["t", *names])]
    lines += [",".join(repr(float(x)) for x in [0.01 * k, *q]) for k, q in enumerate(rows)]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(path)


@pytest.mark.parametrize("kind", ["urdf", "mjcf"])
def test_a_unit_q_gives_numpys_kappa_on_every_entry_point(kind, specs, tmp_path):
    robot = load_robot(specs[kind])
    q = np.array(GOOD[kind])
    w = np.linalg.eigvalsh(pin.crba(robot.model, robot.model.createData(), q))
    result = trajectory_metrics(specs[kind], _csv(tmp_path, specs[kind], [q, q]))
    np.testing.assert_allclose(result.values["kappa"], w[-1] / w[0], rtol=1e-10)
    ones = [n for n in robot.joint_names if robot.model.joints[robot.model.getJointId(n)].nq == 1]
    grid = conditioning_map(specs[kind], ones[:2], grid=2, q=q, ranges=[(0.3, 0.5), (-0.4, 0)])
    assert grid.values["kappa"][0, 0] == pytest.approx(w[-1] / w[0], rel=1e-10)


@pytest.mark.parametrize(("kind", "joint", "q", "norm"), CASES)
def test_conditioning_map_refuses_a_q_off_the_unit_circle(kind, joint, q, norm, specs):
    robot = load_robot(specs[kind])
    ones = [n for n in robot.joint_names if robot.model.joints[robot.model.getJointId(n)].nq == 1]
    with pytest.raises(InputError, match=f"joint '{joint}' in q must be of norm 1") as caught:
        conditioning_map(specs[kind], ones[:2], grid=2, q=q)
    assert caught.value.value == pytest.approx(norm)


@pytest.mark.parametrize(("kind", "joint", "q", "norm"), CASES)
def test_map_trajectory_refuses_a_row_off_the_unit_circle(
    kind, joint, q, norm, specs, tmp_path, capsys
):
    path = _csv(tmp_path, specs[kind], [GOOD[kind], q])
    with pytest.raises(InputError, match=rf"joint '{joint}' in q of .*\(row 2\) must be of norm"):
        trajectory_metrics(specs[kind], path)
    code = main(["map", specs[kind], "--trajectory", path, "-o", str(tmp_path / "out")])
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(lines) == 1 and joint in lines[0] and "row 2" in lines[0], lines
    assert not (tmp_path / "out").exists()
