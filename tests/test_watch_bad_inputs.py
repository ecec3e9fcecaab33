"""Bad input to the watch's constructors and samplers: a GimwatchError in one line, exact text.

The Python side of the bad-input corpus (``test_bad_inputs.py`` covers the command line).
"""

from pathlib import Path

import mujoco
import numpy as np
import pytest

from gimwatch.errors import GimwatchError
from gimwatch.model.mujoco_model import compile_robot
from gimwatch.model.robots import load_robot
from gimwatch.watch.watch import Watch


def mjcf_path(name: str) -> str:
    return str(Path(__file__).parent / "data" / "mjcf" / f"{name}.xml")


UR5 = load_robot("ur5")
MODEL = compile_robot(UR5)
DATA = mujoco.MjData(MODEL)
mujoco.mj_forward(MODEL, DATA)
OTHER_DATA = mujoco.MjData(compile_robot(load_robot(mjcf_path("pendulum3"))))
MATRICES = Watch.from_matrices(2)
DELTA = Watch.from_matrices(2, ("diagonal_ratio",))

CASES = {
    "robot is a pinocchio.Model": (
        lambda: Watch(UR5.model, ("kappa",)),
        "robot must be a gimwatch Robot, got 'pinocchio.pinocchio_pywrap_default.Model' "
        "(Watch.from_model takes a pinocchio.Model, Watch.from_mujoco a MuJoCo pair)",
    ),
    "no robot, no source": (
        lambda: Watch(None, ("kappa",)),
        "robot must be a gimwatch Robot (or a source giving nv), got None",
    ),
    "unknown metric": (
        lambda: Watch(UR5, ("kappa", "condition")),
        "a watched metric must be one of ['diagonal', 'diagonal_ratio', 'eigenvalues', "
        "'kappa', 'kappa_equilibrated', 'kappa_equilibrated_tracked', 'kappa_lanczos', "
        "'kappa_tracked', 'pivot_ratio_backward', 'pivot_ratio_forward', 'rcond', "
        "'scaled_diagonal_ratio', 'stability_margin'], got 'condition'",
    ),
    "alarm on an unwatched metric": (
        lambda: Watch(UR5, ("diagonal_ratio", "diagonal"), alarm_metric="kappa"),
        "alarm_metric must be one of the watched scalar metrics ['diagonal_ratio'], got 'kappa'",
    ),
    "negative threshold": (
        lambda: Watch(UR5, ("kappa",), alarm_metric="kappa", alarm_threshold=-1.0),
        "alarm_threshold must be a finite number > 0, got -1.0",
    ),
    "callback not callable": (
        lambda: Watch(UR5, ("kappa",), alarm_metric="kappa", on_alarm="print"),
        "on_alarm must be a callable taking an Alarm, got 'builtins.str'",
    ),
    "from_model on a Robot": (
        lambda: Watch.from_model(UR5),
        "model must be a pinocchio.Model, got 'gimwatch.model.robots.Robot'",
    ),
    "from_mujoco with data first": (
        lambda: Watch.from_mujoco(DATA, MODEL),
        "model must be a mujoco.MjModel, got 'mujoco._structs.MjData'",
    ),
    "from_mujoco with data of another model": (
        lambda: Watch.from_mujoco(MODEL, OTHER_DATA),
        "data must be the MjData of this MjModel (mujoco.MjData(model)), "
        "got 'an MjData of another model (nq = 3, nv = 3)'",
    ),
    "from_mujoco with a Lanczos metric": (
        lambda: Watch.from_mujoco(MODEL, DATA, ("kappa_lanczos",)),
        "metric 'kappa_lanczos' must be watched on a robot (it runs RNEA/ABA at q), "
        "got 'a watch without one' (use Watch(robot, ...) or Watch.from_model)",
    ),
    "from_matrices of size 0": (
        lambda: Watch.from_matrices(0),
        "nv must be an integer >= 1, got 0",
    ),
    "sample without q": (
        lambda: Watch(UR5, ("kappa",)).sample(0.0),
        "q must be given (a configuration of the robot), got None",
    ),
    "sample with a short q": (
        lambda: Watch(UR5, ("diagonal_ratio",)).sample(0.0, np.zeros(5)),
        "q must be a vector of 6 numbers for ur5, got (5,)",
    ),
    "sample with a NaN in q": (
        lambda: Watch(UR5, ("diagonal_ratio",)).sample(0.0, [0, 0, np.nan, 0, 0, 0]),
        "q must be finite, got [0.0, 0.0, nan, 0.0, 0.0, 0.0]",
    ),
    "MuJoCo sample with a q of the wrong length": (
        lambda: Watch.from_mujoco(MODEL, DATA).sample(0.0, np.zeros(7)),
        "q must be a qpos of 6 numbers (MuJoCo's layout), got (7,)",
    ),
    "MuJoCo sample before mj_forward": (
        lambda: Watch.from_mujoco(MODEL, mujoco.MjData(MODEL)).sample(0.0),
        "data must be an MjData holding M, got 'one that MuJoCo never computed' "
        "(call mujoco.mj_forward(model, data) or mj_step first)",
    ),
    "matrix of the wrong shape": (
        lambda: MATRICES.sample_matrix(0.0, np.eye(3)),
        "M must be a (2, 2) matrix, got 'shape (3, 3)'",
    ),
    "matrix with an inf": (
        lambda: MATRICES.sample_matrix(0.0, [[1.0, np.inf], [np.inf, 1.0]]),
        "M must be finite, got 'inf at (0, 1)'",
    ),
    "matrix not symmetric": (
        lambda: MATRICES.sample_matrix(0.0, [[1.0, 0.5], [0.0, 1.0]]),
        "the GIM must be symmetric, got max|M - M^T| / max|M| = 0.5",
    ),
    "diagonal for a kappa watch": (
        lambda: MATRICES.sample_diagonal(0.0, [1.0, 2.0]),
        "sample_diagonal must be used when no watched metric needs the full M, got 'kappa'",
    ),
    "diagonal with a zero": (
        lambda: DELTA.sample_diagonal(0.0, [1.0, 0.0]),
        "the diagonal must be finite and > 0, got '0.0 at 1'",
    ),
    "matrix for a Lanczos watch": (
        lambda: Watch(UR5, ("kappa_lanczos",)).sample_matrix(0.0, np.eye(6)),
        "metric 'kappa_lanczos' must be sampled with q (it runs RNEA/ABA at q), "
        "got 'a matrix sample'",
    ),
    "sample(t, q) on a matrix watch": (
        lambda: MATRICES.sample(0.0, np.zeros(2)),
        "sample(t, q) must be used on a watch of a robot or a MuJoCo pair, got 'a matrix watch' "
        "(use sample_matrix(t, M) or sample_diagonal(t, d))",
    ),
    "time not a number": (
        lambda: MATRICES.sample_matrix("now", np.eye(2)),
        "t must be a time in seconds, got 'now'",
    ),
    "time not finite": (
        lambda: DELTA.sample_diagonal(np.nan, [1.0, 2.0]),
        "t must be a finite time in seconds, got nan",
    ),
    "unknown series": (
        lambda: MATRICES.array("delta"),
        "the series name must be 't' or a watched metric ['kappa', 'diagonal_ratio'], got 'delta'",
    ),
}


FREE = compile_robot(load_robot("solo12", floating=True))
FREE_DATA = mujoco.MjData(FREE)
mujoco.mj_forward(FREE, FREE_DATA)
ZERO_QUATERNION = FREE.qpos0.copy()
ZERO_QUATERNION[3:7] = 0.0

HOSTILE_CASES = {
    "complex matrix": (
        lambda: MATRICES.sample_matrix(0.0, [[2, 1j], [-1j, 2]]),
        "M must be an array of real numbers, got 'complex128 entries'",
    ),
    "matrix of strings": (
        lambda: MATRICES.sample_matrix(0.0, [["a", "b"], ["c", "d"]]),
        "M must be an array of real numbers, got 'str32 entries'",
    ),
    "complex diagonal": (
        lambda: DELTA.sample_diagonal(0.0, [1 + 1j, 2.0]),
        "the diagonal must be an array of real numbers, got 'complex128 entries'",
    ),
    "qpos of strings": (
        lambda: Watch.from_mujoco(MODEL, DATA).sample(0.0, ["a"] * MODEL.nq),
        "q must be an array of real numbers, got 'str32 entries'",
    ),
    "complex qpos": (
        lambda: Watch.from_mujoco(MODEL, DATA).sample(0.0, np.zeros(MODEL.nq) + 1j),
        "q must be an array of real numbers, got 'complex128 entries'",
    ),
    "zero free-joint quaternion": (
        lambda: Watch.from_mujoco(FREE, FREE_DATA).sample(0.0, ZERO_QUATERNION),
        "the quaternion q[3:7] must be non-zero, got array([0., 0., 0., 0.])",
    ),
    "indefinite matrix to a delta watch": (
        lambda: DELTA.sample_matrix(0.0, [[1.0, 2.0], [2.0, 1.0]]),
        "the GIM must be positive definite (Matrix is not positive definite)",
    ),
}
CASES.update(HOSTILE_CASES)  # issue 27: complex, text, zero quaternions, M not > 0


@pytest.mark.parametrize("case", CASES)
def test_bad_input_to_the_watch_is_one_line(case):
    call, message = CASES[case]
    with pytest.raises(GimwatchError) as info:
        call()
    assert str(info.value) == message
    assert "\n" not in str(info.value)


def test_a_failed_sample_records_nothing():
    watch = Watch.from_matrices(2, ("diagonal_ratio", "kappa"))
    watch.sample_matrix(0.0, np.eye(2))
    with pytest.raises(GimwatchError):
        watch.sample_matrix(1.0, [[1.0, 0.0], [0.0, -1.0]])
    assert watch.array("t").tolist() == [0.0]
    assert [len(v) for v in watch.series.values()] == [1, 1]


def test_a_huge_finite_matrix_has_a_finite_kappa():
    M = np.array([[2.0, 1.0], [1.0, 2.0]]) * 8e307
    watch = Watch.from_matrices(2, ("kappa", "eigenvalues"))
    watch.sample_matrix(0.0, M)
    assert watch.array("kappa")[0] == pytest.approx(3.0, rel=1e-14)
    from gimwatch.metrics.conditioning import condition_number

    assert condition_number(M) == pytest.approx(3.0, rel=1e-14)


def _negative_armature_model():
    xml = """<mujoco><worldbody><body><joint type="hinge" axis="0 0 1" armature="-5"/>
    <geom type="box" size="0.1 0.1 0.1" mass="1"/><body pos="0.5 0 0">
    <joint type="hinge" axis="0 0 1" armature="-5"/><geom type="box" size="0.1 0.1 0.1"
    mass="1"/></body></body></worldbody></mujoco>"""
    model = mujoco.MjModel.from_xml_string(xml)
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    return model, data


@pytest.mark.parametrize("metrics", [("diagonal_ratio",), ("kappa",)])
def test_a_mujoco_m_that_is_not_positive_definite_is_refused(metrics):
    model, data = _negative_armature_model()
    assert np.any(data.M[model.dof_Madr] < 0)  # the case: MuJoCo's M is not > 0
    watch = Watch.from_mujoco(model, data, metrics)
    with pytest.raises(GimwatchError, match="positive"):
        watch.sample(0.0)
    assert watch.array("t").size == 0


@pytest.mark.parametrize("nv", [2, 30])
@pytest.mark.parametrize("metrics", [("kappa",), ("kappa", "eigenvalues")])
def test_a_source_m_that_goes_bad_mid_run_is_refused_by_the_checked_path(nv, metrics):
    """The compiled path reads only diag M for its scale: bad entries off it still fail."""
    watch = Watch.from_matrices(nv, metrics)
    watch.sample_matrix(0.0, np.eye(nv))
    bad = np.eye(nv)
    bad[0, 1] = bad[1, 0] = 1e300  # symmetric, finite, indefinite, far above the diagonal
    with pytest.raises(GimwatchError, match="positive definite"):
        watch.sample_matrix(1.0, bad)
    assert watch.array("t").tolist() == [0.0]
