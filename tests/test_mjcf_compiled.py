"""MJCF read as MuJoCo compiles it: M(q) entry by entry against mj_fullM, and DeNOC's M."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.crosscheck import crosscheck_robot, denoc_model
from gimwatch.denoc import DenocModel
from gimwatch.errors import URDFWarning
from gimwatch.model.denoc_input import instantaneous_urdf
from gimwatch.model.mjcf_coordinates import q_from_qpos, qpos_from_q
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations

mujoco = pytest.importorskip("mujoco")

FEATURES = Path(__file__).parent / "data" / "mjcf" / "features"
MODELS = sorted(FEATURES.glob("*.xml"))


def _mujoco_reference(path, qpos, *, tendon_armature=False):
    """mj_fullM at qpos, straight from MuJoCo (no gimwatch code), free-joint v rotated."""
    model = mujoco.MjModel.from_xml_path(str(path))
    if not tendon_armature and model.ntendon:
        model.tendon_armature[:] = 0
    data = mujoco.MjData(model)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    M = np.zeros((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    T = np.eye(model.nv)
    for j in range(model.njnt):
        if model.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE:
            a, d = model.jnt_qposadr[j], model.jnt_dofadr[j]
            R = np.zeros(9)
            mujoco.mju_quat2Mat(R, qpos[a + 3 : a + 7] / np.linalg.norm(qpos[a + 3 : a + 7]))
            T[d : d + 3, d : d + 3] = R.reshape(3, 3)
    return T.T @ M @ T, model


def _crba(robot, q):
    upper = np.triu(pin.crba(robot.model, robot.model.createData(), q))
    return upper + np.triu(upper, 1).T


def _denoc_gim(robot, q):
    if robot.urdf_xml:
        return denoc_model(robot, rigid=True).gim(q)
    instant = instantaneous_urdf(robot.model, q)
    return DenocModel.from_urdf(instant.urdf, joint_order=instant.joint_order).gim(instant.q)


def _load(path, **kwargs):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)
        return load_robot(str(path), **kwargs)


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_m_equals_mj_fullm_entry_by_entry_in_mujoco_order(path):
    robot = _load(path)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    assert robot.nv == mj_model.nv and robot.nq == mj_model.nq
    names = [
        mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_JOINT, j) or f"joint{j}"
        for j in range(mj_model.njnt)
    ]  # an unnamed joint is joint<id> (unnamed_joints.xml)
    assert robot.joint_names == tuple(names)
    for q in random_configurations(robot, 4, seed=11):
        qpos = qpos_from_q(robot.model, q)
        np.testing.assert_array_equal(q_from_qpos(robot.model, qpos), q)
        reference, _ = _mujoco_reference(path, qpos)
        np.testing.assert_allclose(
            _crba(robot, q), reference, rtol=0, atol=1e-12 * np.abs(reference).max()
        )
        # DeNOC reads the URDF text written from the compiled tree, or with balls and free
        # objects the stand-ins at q
        rigid = reference - np.diag(np.asarray(mj_model.dof_armature))
        np.testing.assert_allclose(
            _denoc_gim(robot, q), rigid, rtol=0, atol=1e-12 * np.abs(rigid).max()
        )


def test_armature_switch_leaves_dof_armature_out():
    path = FEATURES / "includes_defaults.xml"
    with_armature, without = _load(path), _load(path, armature=False)
    q = random_configurations(with_armature, 1, seed=2)[0]
    _, mj_model = _mujoco_reference(path, qpos_from_q(with_armature.model, q))
    assert np.all(mj_model.dof_armature > 0)
    np.testing.assert_allclose(
        _crba(with_armature, q) - _crba(without, q), np.diag(mj_model.dof_armature), atol=1e-15
    )
    assert crosscheck_robot(without, samples=2, seed=0).passed


def test_hinge_ref_makes_q_equal_qpos():
    """At qpos0 (the refs), the pose of every body is the pose written in the file."""
    path = FEATURES / "hopper.xml"
    robot = _load(path)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    assert mj_model.qpos0[1] == 1.25 and mj_model.qpos0[4] == pytest.approx(np.radians(-10))
    data = robot.model.createData()
    pin.framesForwardKinematics(robot.model, data, q_from_qpos(robot.model, mj_model.qpos0))
    mj_data = mujoco.MjData(mj_model)
    mujoco.mj_kinematics(mj_model, mj_data)
    for b in range(1, mj_model.nbody):
        name = mujoco.mj_id2name(mj_model, mujoco.mjtObj.mjOBJ_BODY, b)
        if robot.model.existFrame(name):
            placement = data.oMf[robot.model.getFrameId(name)]
            np.testing.assert_allclose(placement.translation, mj_data.xpos[b], atol=1e-14)


def test_free_objects_are_read_whole_and_body_selects_one_tree():
    path = FEATURES / "humanoid.xml"
    whole = _load(path)
    assert whole.nv == mujoco.MjModel.from_xml_path(str(path)).nv == 24
    robot = _load(path, body="torso")
    assert robot.nv == 18 and robot.mjcf_body == "torso" and "box_free" not in robot.joint_names
    result = crosscheck_robot(robot, samples=2, seed=1)
    assert result.passed and result.mujoco_gim_rel_err < 1e-13, result


def test_ignored_dynamics_are_named_in_one_warning():
    with pytest.warns(URDFWarning) as caught:
        load_robot(str(FEATURES / "humanoid.xml"))
    (warning,) = caught
    assert "1 equality constraint(s), tendon armature" in str(warning.message)


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_crosscheck_compares_denoc_pinocchio_and_mujoco(path):
    robot = _load(path)
    result = crosscheck_robot(robot, samples=2, seed=3)
    assert result.passed, result
    assert result.mujoco_gim_rel_err < 1e-13
    assert result.gim_rel_err < 1e-13 and result.qdd_rel_err is not None
    assert result.tau_rel_err < 1e-12 and result.pivots_rel_err < 1e-12
    assert ("v = 0" in result.note) == (not robot.urdf_xml)


@pytest.mark.parametrize("stem", ["humanoid", "hopper"])
def test_the_watch_on_mujoco_and_on_the_robot_agree(stem):
    """Watch.from_mujoco at MuJoCo's qpos and Watch(robot) at the mapped q give κ and δ of
    NumPy on mj_fullM and on Pinocchio's CRBA respectively, and those two agree."""
    from gimwatch.watch.watch import Watch

    path = FEATURES / f"{stem}.xml"
    robot = _load(path)
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    mj_model.tendon_armature[:] = 0  # gimwatch leaves tendon armature out (warned)
    on_mujoco = Watch.from_mujoco(mj_model, mujoco.MjData(mj_model), robot=robot)
    on_robot = Watch(robot, ("kappa", "diagonal_ratio"))
    from_mujoco, from_crba = [], []
    for t, q in enumerate(random_configurations(robot, 3, seed=4)):
        qpos = qpos_from_q(robot.model, q)
        on_mujoco.sample(t, qpos)
        on_robot.sample(t, q)
        for M, out in (
            (_mujoco_reference(path, qpos)[0], from_mujoco),
            (_crba(robot, q), from_crba),
        ):
            values, diagonal = np.linalg.eigvalsh(M), np.diag(M)
            out.append((values[-1] / values[0], diagonal.max() / diagonal.min()))
    for k, name in enumerate(("kappa", "diagonal_ratio")):
        mujoco_values, crba_values = [r[k] for r in from_mujoco], [r[k] for r in from_crba]
        np.testing.assert_allclose(on_mujoco.array(name), mujoco_values, rtol=1e-10)
        np.testing.assert_allclose(on_robot.array(name), crba_values, rtol=1e-10)
        np.testing.assert_allclose(mujoco_values, crba_values, rtol=1e-10)


def _qpos_text(stem):
    robot = _load(FEATURES / f"{stem}.xml")
    qpos = qpos_from_q(robot.model, random_configurations(robot, 1, seed=9)[0])
    return robot, qpos


@pytest.mark.parametrize("stem", ["humanoid", "hopper"])
def test_analyze_q_takes_mujocos_qpos(stem, capsys):
    import json

    from gimwatch.cli import main

    _, qpos = _qpos_text(stem)
    values = [repr(float(x)) for x in qpos]
    argv = ["analyze", str(FEATURES / f"{stem}.xml"), "--json", "--q", *values]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)
        assert main(argv) == 0
    record = json.loads(capsys.readouterr().out)["configurations"][0]
    reference, _ = _mujoco_reference(FEATURES / f"{stem}.xml", qpos)
    eigenvalues = np.linalg.eigvalsh(reference)
    assert record["kappa"] == pytest.approx(eigenvalues[-1] / eigenvalues[0], rel=1e-9)


@pytest.mark.parametrize("stem", ["humanoid", "hopper"])
def test_simulate_and_survey_run_on_mjcf(stem, tmp_path, capsys):
    from gimwatch.cli import main

    robot, qpos = _qpos_text(stem)
    scene = tmp_path / "scene.toml"
    scene.write_text(
        f'robot = "{FEATURES / f"{stem}.xml"}"\nq = {list(map(float, qpos))}\n'
        "duration = 0.1\nsample = 0.05\n[effects.gravity]\nvector = [0, 0, -9.81]\n"
        '[watch]\nmetrics = ["kappa", "diagonal_ratio"]\n'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)
        assert main(["simulate", str(scene), "-o", str(tmp_path / "run")]) == 0
        first = np.load(tmp_path / "run" / "trajectory.npz")["q"][0]
        np.testing.assert_allclose(first, q_from_qpos(robot.model, qpos), atol=1e-12)
        path = str(FEATURES / f"{stem}.xml")
        assert main(["survey", path, "--samples", "3", "-o", str(tmp_path / "survey")]) == 0
    assert f"{robot.nv}" in (tmp_path / "survey" / "report.md").read_text()


def test_a_files_own_free_joint_is_a_floating_base_for_denoc_and_the_tracker():
    """floating_arm.xml floats on its own free joint: DeNOC's free-flyer, κ tracked by it."""
    from gimwatch.simulation.backends import DenocBackend
    from gimwatch.watch import Watch

    robot = _load(FEATURES / "floating_arm.xml")
    assert robot.free_base and not robot.floating and robot.joint_names[0] == "float"
    assert "base='floating'" in repr(robot)
    backend = DenocBackend(robot, np.array(robot.model.gravity.linear))
    watch = Watch(robot, ("kappa_tracked",))
    rng = np.random.default_rng(4)
    for t, q in enumerate(random_configurations(robot, 3, seed=5)):
        v, tau = rng.standard_normal(robot.nv), rng.standard_normal(robot.nv)
        reference = pin.aba(robot.model, robot.model.createData(), q, v, tau)
        np.testing.assert_allclose(backend.forward_dynamics(q, v, tau), reference, atol=1e-11)
        eigenvalues = np.linalg.eigvalsh(_crba(robot, q))
        watch.sample(float(t), q)
        kappa = watch.arrays()["watch_kappa_tracked"][-1]
        assert kappa == pytest.approx(eigenvalues[-1] / eigenvalues[0], rel=1e-9)


def test_analyze_says_floating_for_a_files_own_free_joint(capsys):
    from gimwatch.cli import main

    assert main(["analyze", str(FEATURES / "floating_arm.xml")]) == 0
    assert "nv = 8, floating base" in capsys.readouterr().out


def test_a_scene_selects_one_tree_with_body_and_leaves_armature_out(tmp_path, capsys):
    from gimwatch.cli import main

    scene = tmp_path / "scene.toml"
    scene.write_text(
        f'robot = "{FEATURES / "humanoid.xml"}"\nbody = "torso"\narmature = false\n'
        'duration = 0.02\nsample = 0.01\n[watch]\nmetrics = ["kappa"]\n'
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)
        assert main(["simulate", str(scene), "-o", str(tmp_path / "run")]) == 0
    q = np.load(tmp_path / "run" / "trajectory.npz")["q"]
    reference = _load(FEATURES / "humanoid.xml", body="torso", armature=False)
    assert q.shape[1] == reference.nq and reference.nv == 18  # box_free left out
    M = _crba(reference, q[0])
    eigenvalues = np.linalg.eigvalsh(M)
    kappa = np.load(tmp_path / "run" / "trajectory.npz")["watch_kappa"][0]
    assert kappa == pytest.approx(eigenvalues[-1] / eigenvalues[0], rel=1e-10)
    capsys.readouterr()
    scene.write_text(scene.read_text().replace('"torso"', '"no_such_body"'))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", URDFWarning)
        assert main(["simulate", str(scene), "-o", str(tmp_path / "bad")]) == 2
    err = capsys.readouterr().err.strip()
    assert "no_such_body" in err and "body" in err and len(err.splitlines()) == 1, err


def test_unnamed_joints_map_between_mujoco_and_the_robot():
    """Watch.from_mujoco(robot=...) finds MuJoCo's unnamed joints by their joint<id> names."""
    from gimwatch.watch import Watch

    path = FEATURES / "unnamed_joints.xml"
    robot = _load(path)
    assert robot.joint_names == ("joint0", "joint1", "named")
    mj_model = mujoco.MjModel.from_xml_path(str(path))
    mj_data = mujoco.MjData(mj_model)
    mj_data.qpos[:] = [0.3, -0.2, 0.1]
    mujoco.mj_forward(mj_model, mj_data)
    M = np.zeros((mj_model.nv, mj_model.nv))
    mujoco.mj_fullM(mj_model, mj_data, M)
    eigenvalues = np.linalg.eigvalsh(M)
    watch = Watch.from_mujoco(mj_model, mj_data, ("kappa",), robot=robot)
    watch.sample(0.0)
    kappa = watch.arrays()["watch_kappa"][0]
    assert kappa == pytest.approx(eigenvalues[-1] / eigenvalues[0], rel=1e-12)
    assert crosscheck_robot(robot, samples=2, peer="mujoco").mujoco_gim_rel_err < 1e-13


@pytest.mark.parametrize("path", MODELS, ids=[p.stem for p in MODELS])
def test_the_watch_keeps_mujocos_armature_in_delta_and_the_tracked_kappa(path):
    """δ and κ tracked by Watch(robot) and Watch.from_model: those of CRBA's M, armature in.

    DeNOC models rigid bodies: a robot with armature is watched through Pinocchio.
    """
    from gimwatch.watch import Watch

    robot = _load(path)
    for q in random_configurations(robot, 2, seed=8):
        M = _crba(robot, q)
        eigenvalues, diagonal = np.linalg.eigvalsh(M), np.diag(M)
        watch = Watch(robot, ("diagonal_ratio", "kappa_tracked"))
        from_model = Watch.from_model(robot.model, ("diagonal_ratio",))
        watch.sample(0.0, q)
        from_model.sample(0.0, q)
        delta = diagonal.max() / diagonal.min()
        assert watch.arrays()["watch_diagonal_ratio"][0] == pytest.approx(delta, rel=1e-12)
        assert from_model.arrays()["watch_diagonal_ratio"][0] == pytest.approx(delta, rel=1e-12)
        kappa = eigenvalues[-1] / eigenvalues[0]
        assert watch.arrays()["watch_kappa_tracked"][0] == pytest.approx(kappa, rel=1e-9)
