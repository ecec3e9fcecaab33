"""DeNOC's O(n) recursions with free joints on any body and several trees (issue 40).

References are independent of DeNOC: MuJoCo's ``mj_fullM`` and ``mj_solveM`` on MJCF files
written here (80 free boxes, nv = 480; several trees of free bodies, hinges and slides),
NumPy's κ of MuJoCo's M, and Pinocchio's CRBA, RNEA and ABA on a model composed with free
joints below the root. MuJoCo's free-joint linear velocity is in the world frame, gimwatch's
(Pinocchio's) in the body frame: M = Tᵀ M_mj T with T the body's rotation on that block,
built here from MuJoCo's own ``mju_quat2Mat``.
"""

from __future__ import annotations

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import DenocModel, body_tree
from gimwatch.errors import RobotError
from gimwatch.metrics.analyze import analyze
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.metrics.tracker import extreme_eigenvalues
from gimwatch.model.denoc_input import tree_arrays
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot


def _boxes(n: int, seed: int = 0) -> str:
    """N free boxes of random size, mass and place (nv = 6 N)."""
    rng = np.random.default_rng(seed)
    bodies = []
    for i in range(n):
        pos, size = rng.uniform(-2, 2, 3), rng.uniform(0.05, 0.3, 3)
        bodies.append(
            f'<body name="box{i}" pos="{pos[0]:.3f} {pos[1]:.3f} {pos[2]:.3f}">'
            f'<freejoint name="free{i}"/><geom type="box" mass="{rng.uniform(0.1, 3):.3f}" '
            f'size="{size[0]:.3f} {size[1]:.3f} {size[2]:.3f}"/></body>'
        )
    return f'<mujoco model="boxes{n}"><worldbody>{"".join(bodies)}</worldbody></mujoco>'


def _trees(free: int, arms: int) -> str:
    """Free bases with a hinge and a slide below each, fixed-base arms and ball-joint ropes."""
    parts = []
    for t in range(free):
        parts.append(
            f'<body name="base{t}" pos="{t} 0 1" euler="{5 * t} 10 0"><freejoint name="fb{t}"/>'
            '<geom type="box" size="0.2 0.1 0.05" mass="2"/>'
            f'<body name="leg{t}" pos="0.2 0 0"><joint name="h{t}" type="hinge" axis="0 1 0"/>'
            '<geom type="capsule" fromto="0 0 0 0.3 0 0" size="0.03" mass="0.5"/>'
            f'<body name="foot{t}" pos="0.3 0 0" euler="10 20 30">'
            f'<joint name="s{t}" type="slide" axis="1 0 0"/>'
            '<geom type="sphere" size="0.05" mass="0.2"/></body></body></body>'
        )
    for t in range(arms):
        parts.append(
            f'<body name="arm{t}" pos="0 {t + 1} 0"><joint name="a{t}" axis="0 0 1"/>'
            '<geom type="capsule" fromto="0 0 0 0.5 0 0" size="0.04" mass="1"/>'
            f'<body name="fore{t}" pos="0.5 0 0"><joint name="b{t}" axis="0 1 1"/>'
            '<geom type="box" size="0.2 0.05 0.05" mass="0.7" pos="0.2 0 0"/></body></body>'
        )
    parts.append(  # a rope of ball joints hanging from the world, and one from a free body
        '<body name="rope0" pos="0 -1 2"><joint name="r0" type="ball"/>'
        '<geom type="capsule" fromto="0 0 0 0 0 -0.3" size="0.02" mass="0.3"/>'
        '<body name="rope1" pos="0 0 -0.3"><joint name="r1" type="ball"/>'
        '<geom type="capsule" fromto="0 0 0 0.1 0 -0.3" size="0.02" mass="0.2"/></body></body>'
        '<body name="kite" pos="1 -1 2"><freejoint name="kite_free"/>'
        '<geom type="box" size="0.3 0.2 0.01" mass="0.4"/>'
        '<body name="tail" pos="0 -0.2 0"><joint name="tail_ball" type="ball"/>'
        '<geom type="capsule" fromto="0 0 0 0 -0.4 0" size="0.01" mass="0.05"/></body></body>'
    )
    return f'<mujoco model="trees"><worldbody>{"".join(parts)}</worldbody></mujoco>'


@pytest.fixture(scope="module", params=["boxes80", "trees"])
def mjcf_file(request, tmp_path_factory):
    text = _boxes(80) if request.param == "boxes80" else _trees(free=6, arms=3)
    path = tmp_path_factory.mktemp("mjcf") / f"{request.param}.xml"
    path.write_text(text)
    return path


def _random_qpos(mj: mujoco.MjModel, rng) -> np.ndarray:
    qpos = np.empty(mj.nq)
    for j in range(mj.njnt):
        a = mj.jnt_qposadr[j]
        quaternion = rng.standard_normal(4)
        quaternion /= np.linalg.norm(quaternion)
        if mj.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            qpos[a : a + 7] = [*rng.uniform(-2, 2, 3), *quaternion]
        elif mj.jnt_type[j] == mujoco.mjtJoint.mjJNT_BALL:  # ω in the body frame, as ours
            qpos[a : a + 4] = quaternion
        else:
            qpos[a] = rng.uniform(-3, 3)
    return qpos


def _mujoco_at(mj: mujoco.MjModel, qpos: np.ndarray):
    """MuJoCo's dense M(qpos), its factor in ``data``, and T (qvel = T v)."""
    data = mujoco.MjData(mj)
    data.qpos[:] = qpos
    mujoco.mj_kinematics(mj, data)
    mujoco.mj_comPos(mj, data)
    mujoco.mj_makeM(mj, data)
    mujoco.mj_factorM(mj, data)
    full = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, full)
    T = np.eye(mj.nv)
    rotation = np.empty(9)
    for j in np.flatnonzero(mj.jnt_type == mujoco.mjtJoint.mjJNT_FREE):
        a, v = mj.jnt_qposadr[j], mj.jnt_dofadr[j]
        mujoco.mju_quat2Mat(rotation, qpos[a + 3 : a + 7])
        T[v : v + 3, v : v + 3] = rotation.reshape(3, 3)
    return full, data, T


def _q_of(mj: mujoco.MjModel, qpos: np.ndarray) -> np.ndarray:
    """Gimwatch's q: MuJoCo's qpos with each quaternion (w, x, y, z) as (x, y, z, w)."""
    q = qpos.copy()
    free, ball = int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL)
    for j in range(mj.njnt):
        kind = int(mj.jnt_type[j])
        if kind in (free, ball):
            a = mj.jnt_qposadr[j] + (3 if kind == free else 0)
            q[a : a + 4] = np.roll(qpos[a : a + 4], -1)
    return q


def test_m_and_its_inverse_equal_mujocos(mjcf_file):
    """M (dense NumPy and O(n) compiled columns), diag M and M⁻¹ x equal MuJoCo's, 1e-12."""
    mj = mujoco.MjModel.from_xml_path(str(mjcf_file))
    robot = load_robot(str(mjcf_file))
    model = denoc_model(robot)
    assert model.nv == mj.nv and model.free_joints
    rng = np.random.default_rng(7)
    for _ in range(2):
        qpos = _random_qpos(mj, rng)
        full, data, T = _mujoco_at(mj, qpos)
        expected = T.T @ full @ T
        q = _q_of(mj, qpos)
        scale = np.abs(expected).max()
        assert np.abs(model.gim(q) - expected).max() <= 1e-12 * scale
        state = model.state(q)  # the O(n) operators, internal order
        columns = np.column_stack(
            [model.to_public(state.matvec(model.to_internal("x", e))) for e in np.eye(model.nv)]
        )
        assert np.abs(columns - expected).max() <= 1e-12 * scale
        assert np.abs(model.to_public(state.diagonal()) - np.diag(expected)).max() <= 1e-12 * scale
        y = rng.standard_normal((1, mj.nv))
        solved = np.empty_like(y)
        mujoco.mj_solveM(mj, data, solved, (T @ y[0])[None])  # M_mj⁻¹ T y
        x = model.to_public(state.solve(model.to_internal("y", y[0])))
        reference = T.T @ solved[0]
        error = np.abs(x - reference).max() / np.abs(reference).max()
        assert error <= 1e-12, error


def test_kappa_on_the_o_n_path_equals_numpys_of_mujocos_m(mjcf_file):
    """κ by Lanczos on the O(n) products equals NumPy's cond of mj_fullM (1e-8)."""
    mj = mujoco.MjModel.from_xml_path(str(mjcf_file))
    qpos = _random_qpos(mj, np.random.default_rng(3))
    full, _, _ = _mujoco_at(mj, qpos)
    analysis = analyze(str(mjcf_file), q=list(qpos), backend="denoc")
    assert analysis.path == "denoc"
    assert analysis.results[0].kappa == pytest.approx(np.linalg.cond(full), rel=1e-8)


def test_auto_takes_files_above_the_data_limit_to_the_o_n_path(tmp_path):
    """80 free boxes (nv = 480 > 400): ``auto`` chooses DeNOC; ``crba`` names the limit."""
    path = tmp_path / "boxes80.xml"
    path.write_text(_boxes(80))
    analysis = analyze(str(path), random=1, seed=0)
    assert (analysis.path, analysis.chosen, analysis.results[0].nv) == ("denoc", True, 480)
    assert analysis.floating is False  # 80 trees: no one free base
    with pytest.raises(RobotError, match=f"DATA_NV_LIMIT = {DATA_NV_LIMIT}.*'denoc'"):
        analyze(str(path), backend="crba")


def test_a_joint_without_a_recursion_is_refused_by_name():
    """A planar joint (Pinocchio's; no MJCF or URDF joint makes one) is named, not misread."""
    model = pin.Model()
    k = model.addJoint(0, pin.JointModelPlanar(), pin.SE3.Identity(), "sled")
    model.appendBodyToJoint(k, pin.Inertia.Random(), pin.SE3.Identity())
    with pytest.raises(RobotError, match="'sled' \\(Planar\\) has no O\\(n\\) DeNOC"):
        tree_arrays(model, source="planar")


def _composed_model() -> pin.Model:
    """Free joints at the root and below a hinge, ball joints, a tree with its own free joint."""
    rng = np.random.default_rng(1)
    model = pin.Model()

    def add(parent, joint, name):
        placement = pin.SE3(pin.rpy.rpyToMatrix(*rng.standard_normal(3)), rng.standard_normal(3))
        k = model.addJoint(parent, joint, placement, name)
        inertia = pin.Inertia(
            rng.uniform(0.5, 2), rng.standard_normal(3) * 0.2, np.diag(rng.uniform(0.1, 1, 3))
        )
        model.appendBodyToJoint(k, inertia, pin.SE3.Identity())
        return k

    axis = np.array([0.3, 0.4, 0.5]) / np.linalg.norm([0.3, 0.4, 0.5])
    # joints depth first: Pinocchio's CRBA reads each subtree as contiguous velocity columns
    a = add(0, pin.JointModelFreeFlyer(), "free_a")
    add(a, pin.JointModelRZ(), "hinge_h")
    b = add(a, pin.JointModelRY(), "hinge_b")
    c = add(b, pin.JointModelFreeFlyer(), "free_c")  # six DoF of a body that is no root
    d = add(c, pin.JointModelPrismaticUnaligned(axis), "slide_d")
    add(d, pin.JointModelSpherical(), "ball_i")
    e = add(0, pin.JointModelRX(), "hinge_e")
    add(e, pin.JointModelRUBZ(), "continuous_f")
    g = add(0, pin.JointModelFreeFlyer(), "free_g")
    ball = add(g, pin.JointModelSpherical(), "ball_j")
    add(ball, pin.JointModelFreeFlyer(), "free_k")  # six DoF below a ball
    return model


def test_free_joints_below_the_root_against_pinocchio():
    """CRBA's M, RNEA's τ, ABA's q̈ (gravity, v ≠ 0), the energy and κ of a composed model."""
    model = _composed_model()
    data = model.createData()
    denoc = DenocModel(body_tree(tree_arrays(model, source="composed")), model.names[1:])
    rng = np.random.default_rng(2)
    gravity = np.array([0.0, 0.0, -9.81])
    for _ in range(3):
        q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
        v, tau, a = (rng.standard_normal(model.nv) for _ in range(3))
        pin.crba(model, data, q)
        M = np.triu(data.M) + np.triu(data.M, 1).T
        assert np.abs(denoc.gim(q) - M).max() <= 1e-12 * np.abs(M).max()
        assert np.allclose(
            denoc.inverse_dynamics(q, v, a, gravity=gravity),
            pin.rnea(model, data, q, v, a),
            rtol=0,
            atol=1e-12 * np.abs(M).max() * 10,
        )
        qdd = denoc.forward_dynamics(q, v, tau, gravity=gravity)
        assert np.abs(qdd - pin.aba(model, data, q, v, tau)).max() <= 1e-11 * np.abs(qdd).max()
        kappa = extreme_eigenvalues(denoc.state(q)).kappa
        assert kappa == pytest.approx(np.linalg.cond(M), rel=1e-8)
        kinetic, potential = denoc.energy(q, v, gravity=gravity)
        assert kinetic == pytest.approx(pin.computeKineticEnergy(model, data, q, v), rel=1e-12)
        assert potential == pytest.approx(pin.computePotentialEnergy(model, data, q), rel=1e-12)


def test_the_limits_page_states_the_limits_of_the_code():
    """docs/limits.md quotes DATA_NV_LIMIT and LINEAR_NV_LIMIT as the code has them."""
    import re
    from pathlib import Path

    from gimwatch.metrics.analyze import LINEAR_NV_LIMIT

    page = (Path(__file__).parents[1] / "docs" / "limits.md").read_text()
    assert int(re.search(r"\*\*`DATA_NV_LIMIT` = (\d+)\*\*", page).group(1)) == DATA_NV_LIMIT
    assert re.search(r"\| nv ≤ (\d+) \| nv > \1 \|", page).group(1) == str(DATA_NV_LIMIT)
    quoted = re.search(r"`LINEAR_NV_LIMIT` = ([\d,]+) coordinates", page).group(1)
    assert int(quoted.replace(",", "")) == LINEAR_NV_LIMIT
    assert re.search(r"80 free boxes,\s+nv = 480", page) and _boxes(80).count("<freejoint") == 80


def test_the_tracker_certifies_kappa_on_trees_of_free_and_ball_joints(tmp_path):
    """The κ tracker on DeNOC's compiled model of free/ball joints: every sample certified and
    within its bracket of NumPy's κ of MuJoCo's M, along a path between two random poses."""
    from gimwatch.metrics.tracker import KappaTracker
    from gimwatch.metrics.tracker.providers import lean_model

    path = tmp_path / "trees.xml"
    path.write_text(_trees(free=3, arms=2))
    mj = mujoco.MjModel.from_xml_path(str(path))
    robot = load_robot(str(path))
    lean = lean_model(robot)
    assert lean is not None and lean.nv == mj.nv
    tracker = KappaTracker(lean, robot.nv)
    rng = np.random.default_rng(5)
    start, end = _random_qpos(mj, rng), _random_qpos(mj, rng)
    for s in np.linspace(0.0, 1.0, 12):
        qpos = (1 - s) * start + s * end
        for j in range(mj.njnt):  # quaternions back on the unit sphere
            kind, a = int(mj.jnt_type[j]), mj.jnt_qposadr[j]
            if kind in (int(mujoco.mjtJoint.mjJNT_FREE), int(mujoco.mjtJoint.mjJNT_BALL)):
                a += 3 if kind == int(mujoco.mjtJoint.mjJNT_FREE) else 0
                qpos[a : a + 4] /= np.linalg.norm(qpos[a : a + 4])
        full, _, _ = _mujoco_at(mj, qpos)
        exact = np.linalg.cond(full)
        sample = tracker.sample(_q_of(mj, qpos))
        assert sample.certified, s
        assert sample.kappa * (1 - 1e-9) <= exact <= sample.kappa * (1 + sample.error_estimate)
