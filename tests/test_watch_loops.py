"""The watch in a user's loop: each constructor against an independent computation of κ and δ."""

import sys
import warnings
from pathlib import Path

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from gimwatch.errors import IllConditionedWarning, InputError
from gimwatch.model.inertia import gim
from gimwatch.model.mujoco_model import _joint_maps, compile_robot
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch.alarm import DEFAULT_ALARM_THRESHOLD
from gimwatch.watch.watch import Watch


def mjcf_path(name: str) -> str:
    return str(Path(__file__).parent / "data" / "mjcf" / f"{name}.xml")


def _kappa_delta(M):
    """κ and δ by plain NumPy: the reference."""
    values = np.linalg.eigvalsh(M)
    return values[-1] / values[0], np.diag(M).max() / np.diag(M).min()


@pytest.mark.parametrize(
    ("spec", "floating"),
    # g1 (nv = 35): the watch's κ there is LAPACK dsyevd from SciPy, not the numba kernel
    [("ur5", False), (mjcf_path("panda"), False), (mjcf_path("solo12"), True), ("g1", True)],
)
def test_a_mujoco_watch_gives_the_kappa_and_delta_of_gimwatchs_crba(spec, floating):
    robot = load_robot(spec, floating=floating)
    model = compile_robot(robot)
    armature = np.full(model.nv, 0.05)
    model.dof_armature[:] = armature
    data = mujoco.MjData(model)
    plain = Watch.from_mujoco(model, data, armature=False)  # MuJoCo's coordinates
    mapped = Watch.from_mujoco(model, data, ("kappa", "diagonal_ratio"), robot=robot)
    delta_only = Watch.from_mujoco(model, data, ("diagonal_ratio",), armature=False)
    kappa_only = Watch.from_mujoco(model, data, ("kappa",), armature=False)
    qs = random_configurations(robot, 4, seed=11)
    for k, q in enumerate(qs):
        qpos = np.array(model.qpos0)
        _joint_maps(robot, model, q, qpos, np.zeros((model.nv, robot.nv)))
        data.qpos[:] = qpos
        mujoco.mj_forward(model, data)
        for watch in (plain, mapped, delta_only, kappa_only):
            watch.sample(0.1 * k)
    references = [_kappa_delta(gim(robot, q)) for q in qs]
    with_armature = [_kappa_delta(gim(robot, q) + np.diag(armature)) for q in qs]
    np.testing.assert_allclose(plain.array("kappa"), [r[0] for r in references], rtol=1e-9)
    np.testing.assert_allclose(kappa_only.array("kappa"), [r[0] for r in references], rtol=1e-9)
    np.testing.assert_allclose(
        plain.array("diagonal_ratio"), [r[1] for r in references], rtol=1e-12
    )
    np.testing.assert_allclose(
        delta_only.array("diagonal_ratio"), [r[1] for r in references], rtol=1e-12
    )
    np.testing.assert_allclose(mapped.array("kappa"), [r[0] for r in with_armature], rtol=1e-9)
    np.testing.assert_allclose(
        mapped.array("diagonal_ratio"), [r[1] for r in with_armature], rtol=1e-12
    )
    np.testing.assert_allclose(mapped.array("t"), 0.1 * np.arange(4))


def _pinocchio_references(robot, qs) -> dict[str, list]:
    """κ, δ, diag M and the forward pivot ratio by NumPy on Pinocchio's CRBA at each q."""
    data = robot.model.createData()
    out = {"kappa": [], "diagonal_ratio": [], "diagonal": [], "pivot_ratio_forward": []}
    for q in qs:
        upper = pin.crba(robot.model, data, q)
        M = np.triu(upper) + np.triu(upper, 1).T
        kappa, delta = _kappa_delta(M)
        pivots = np.diag(np.linalg.cholesky(M)) ** 2
        out["kappa"].append(kappa)
        out["diagonal_ratio"].append(delta)
        out["diagonal"].append(np.diag(M))
        out["pivot_ratio_forward"].append(pivots.max() / pivots.min())
    return out


def test_a_mujoco_watch_at_a_given_qpos_is_the_robot_watch_at_q():
    robot = load_robot("ur5")
    model = compile_robot(robot)
    data = mujoco.MjData(model)
    metrics = ("kappa", "diagonal_ratio", "diagonal")
    on_mujoco = Watch.from_mujoco(model, data, metrics, robot=robot)
    on_robot = Watch(robot, metrics)
    qs = random_configurations(robot, 3, seed=2)
    for k, q in enumerate(qs):
        on_mujoco.sample(float(k), q)  # ur5: every joint revolute, qpos = q
        on_robot.sample(float(k), q)
    references = _pinocchio_references(robot, qs)
    for name in metrics:  # κ ≈ 1e2 here; MuJoCo's M differs from CRBA's by round-off
        np.testing.assert_allclose(on_mujoco.array(name), references[name], rtol=1e-9)
        np.testing.assert_allclose(on_robot.array(name), references[name], rtol=1e-9)
    assert on_mujoco.dof_names == on_robot.dof_names


@pytest.mark.parametrize(
    "metrics", [("kappa", "diagonal_ratio", "pivot_ratio_forward"), ("diagonal_ratio",)]
)
def test_a_pinocchio_model_watch_is_the_robot_watch(metrics):
    robot = load_robot(mjcf_path("solo12"), floating=True)
    on_model = Watch.from_model(robot.model, metrics)
    on_robot = Watch(robot, metrics)
    qs = random_configurations(robot, 3, seed=4)
    for k, q in enumerate(qs):
        on_model.sample(float(k), q)
        on_robot.sample(float(k), q)
    references = _pinocchio_references(robot, qs)
    for name in metrics:  # κ up to 3.2e4: eps·κ ≈ 7e-12, so 1e-10 leaves a margin of 14
        np.testing.assert_allclose(on_model.array(name), references[name], rtol=1e-10)
        np.testing.assert_allclose(on_robot.array(name), references[name], rtol=1e-10)
    assert on_model.robot.floating and on_model.dof_names == robot.dof_names


def test_a_matrix_watch_is_the_plain_formulas():
    rng = np.random.default_rng(8)
    metrics = ("kappa", "diagonal_ratio", "eigenvalues", "diagonal")
    watch = Watch.from_matrices(5, metrics)
    delta_only = Watch.from_matrices(5, ("diagonal_ratio",))
    matrices = []
    for k in range(4):
        A = rng.standard_normal((5, 5))
        M = A @ A.T + 0.1 * np.eye(5)
        matrices.append(M)
        watch.sample_matrix(float(k), M)
        delta_only.sample_diagonal(float(k), np.diag(M))
    expected = np.array([_kappa_delta(M) for M in matrices])
    np.testing.assert_allclose(watch.array("kappa"), expected[:, 0], rtol=1e-9)
    np.testing.assert_allclose(watch.array("diagonal_ratio"), expected[:, 1], rtol=1e-15)
    np.testing.assert_allclose(delta_only.array("diagonal_ratio"), expected[:, 1], rtol=1e-15)
    np.testing.assert_allclose(watch.array("diagonal"), [np.diag(M) for M in matrices])
    np.testing.assert_allclose(
        watch.array("eigenvalues"), [np.linalg.eigvalsh(M) for M in matrices], rtol=1e-9
    )


#: κ of diag(1, 1/s) is s: up through 100 twice, down once.
KAPPAS = [1.0, 50.0, 150.0, 300.0, 80.0, 99.0, 101.0, 500.0]


def _upward_crossings(values, threshold):
    above = [v > threshold for v in values]
    return [k for k, a in enumerate(above) if a and (k == 0 or not above[k - 1])]


def test_the_callback_fires_once_per_upward_crossing():
    seen = []
    watch = Watch.from_matrices(
        2, ("kappa",), alarm_metric="kappa", alarm_threshold=100.0, on_alarm=seen.append
    )
    returned = [
        watch.sample_matrix(float(k), np.diag([1.0, 1.0 / s])) for k, s in enumerate(KAPPAS)
    ]
    crossings = _upward_crossings(KAPPAS, 100.0)
    assert crossings == [2, 6]
    assert [a.time_s for a in seen] == [float(k) for k in crossings]
    assert [a.value for a in seen] == pytest.approx([KAPPAS[k] for k in crossings], rel=1e-12)
    assert [a for a in returned if a is not None] == seen == watch.alarms
    assert all(a.threshold == 100.0 and a.metric == "kappa" for a in seen)


def test_the_warning_comes_once_per_upward_crossing():
    watch = Watch.from_matrices(2, ("kappa",), alarm_metric="kappa", alarm_threshold=100.0)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for k, s in enumerate(KAPPAS):
            watch.sample_matrix(float(k), np.diag([1.0, 1.0 / s]))
    assert [w.category for w in caught] == [IllConditionedWarning] * 2
    assert str(caught[0].message) == (
        "watch: kappa = 150 crossed the alarm threshold 100 at t = 2 s"
    )
    assert caught[0].filename == __file__  # points at the caller's sample line


def test_the_default_threshold_is_the_documented_ill_conditioning_one():
    assert DEFAULT_ALARM_THRESHOLD * np.finfo(float).eps == pytest.approx(1e-2)
    calls = []
    quiet = Watch.from_matrices(
        2, ("diagonal_ratio",), alarm_metric="diagonal_ratio", on_alarm=calls.append
    )
    loud = Watch.from_matrices(2, ("diagonal_ratio",), alarm_metric="diagonal_ratio")
    both = Watch.from_matrices(
        2, ("diagonal_ratio",), alarm_metric="diagonal_ratio", on_alarm=calls.append, warn=True
    )
    below, above = np.array([1.0, 1e-13]), np.array([1.0, 1e-14])  # δ = 1e13, 1e14
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        for watch in (quiet, loud, both):
            watch.sample_diagonal(0.0, below)
            watch.sample_diagonal(1.0, above)
    assert len(calls) == 2 and len(caught) == 2
    assert "crossed the alarm threshold 4.5e+13 at t = 1 s (kappa*eps >= 0.01" in str(
        caught[0].message
    )


def test_a_simulation_still_reports_its_alarms_without_warning():
    from gimwatch.simulation.scene import parse_scene
    from gimwatch.simulation.simulate import run_scene

    scene = parse_scene(
        {
            "robot": "chain:3",
            "duration": 0.02,
            "sample": 0.01,
            "integrator": {"method": "RK4", "dt": 0.01},
            "watch": {"metrics": ["kappa"], "alarm_metric": "kappa", "alarm_threshold": 1.0},
        },
        source="<test>",
    )
    with warnings.catch_warnings():
        warnings.simplefilter("error", IllConditionedWarning)
        run = run_scene(scene)
    assert len(run.alarms) == 1


def test_the_dataframe_holds_the_arrays():
    pytest.importorskip("pandas", reason="to_dataframe() needs the pandas extra")
    watch = Watch.from_matrices(3, ("kappa", "diagonal_ratio", "diagonal"))
    rng = np.random.default_rng(1)
    for k in range(5):
        A = rng.standard_normal((3, 3))
        watch.sample_matrix(0.5 * k, A @ A.T + np.eye(3))
    frame = watch.to_dataframe()
    assert list(frame.columns) == [
        "t",
        "kappa",
        "diagonal_ratio",
        "diagonal:0",
        "diagonal:1",
        "diagonal:2",
    ]
    np.testing.assert_array_equal(frame["t"].to_numpy(), watch.array("t"))
    np.testing.assert_array_equal(frame["kappa"].to_numpy(), watch.array("kappa"))
    np.testing.assert_array_equal(frame["diagonal_ratio"].to_numpy(), watch.array("diagonal_ratio"))
    np.testing.assert_array_equal(
        frame[["diagonal:0", "diagonal:1", "diagonal:2"]].to_numpy(), watch.array("diagonal")
    )


def test_the_dataframe_without_pandas_names_the_extra(monkeypatch):
    watch = Watch.from_matrices(2, ("kappa",))
    monkeypatch.setitem(sys.modules, "pandas", None)
    with pytest.raises(InputError) as info:
        watch.to_dataframe()
    assert str(info.value) == (
        "to_dataframe() must be usable with pandas installed, got 'pandas missing' "
        "(pip install 'gimwatch[pandas]')"
    )


def test_a_delta_only_mujoco_watch_forms_no_matrix(monkeypatch):
    robot = load_robot("ur5")
    model = compile_robot(robot)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    watch = Watch.from_mujoco(model, data, ("diagonal_ratio",))

    def refuse(*args):
        raise AssertionError("M formed for a δ-only watch")

    monkeypatch.setattr(mujoco, "mj_fullM", refuse)
    monkeypatch.setattr(np.linalg, "eigvalsh", refuse)
    watch.sample(0.0)
    watch.sample(0.1, data.qpos)
    M = gim(robot, data.qpos)
    assert watch.array("diagonal_ratio") == pytest.approx(
        [np.diag(M).max() / np.diag(M).min()] * 2, rel=1e-12
    )


def test_a_pinocchio_aba_loop_watches_like_gimwatch():
    """The docs' loop, checked: the watch's κ at each sample is κ of pin.crba there."""
    model = load_robot("ur5").model
    data = model.createData()
    watch = Watch.from_model(model, ("kappa",))
    q, v, dt, reference = pin.neutral(model), np.zeros(model.nv), 1e-3, []
    for k in range(200):
        if k % 50 == 0:
            watch.sample(k * dt, q)
            reference.append(np.linalg.cond(pin.crba(model, model.createData(), q)))
        v += dt * pin.aba(model, data, q, v, np.zeros(model.nv))
        q = pin.integrate(model, q, dt * v)
    np.testing.assert_allclose(watch.array("kappa"), reference, rtol=1e-9)
    assert watch.array("t") == pytest.approx([0.0, 0.05, 0.1, 0.15])
