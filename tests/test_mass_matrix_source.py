"""The declared MassMatrixSource: each implementation against an independent M, and a watch
driven by a source written here (one with every optional path left undeclared)."""

import math

import mujoco
import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import DenocModel
from gimwatch.metrics.mass_matrix_sources import DenocDiagonal, DenocLinear, PinocchioSource
from gimwatch.metrics.registry import METRICS, GimState, Metric, evaluate
from gimwatch.model.mass_matrix_source import MassMatrixSource
from gimwatch.model.mujoco_model import compile_robot
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.backends import make_backend
from gimwatch.watch.sources import GivenMatrix, MujocoSource
from gimwatch.watch.watch import OPERATOR_METRICS, Watch


def _crba(robot, q):
    """Pinocchio's CRBA on a fresh Data, upper triangle mirrored: the reference M."""
    M = pin.crba(robot.model, robot.model.createData(), q)
    return np.triu(M) + np.triu(M, 1).T


def _udut_pivots(M):
    """Pivots of M = U D Uᵀ by NumPy: Cholesky of M with its order reversed."""
    reverse = M[::-1, ::-1]
    return (np.diag(np.linalg.cholesky(reverse)) ** 2)[::-1]


@pytest.fixture(scope="module")
def chain():
    robot = load_robot("chain:5")
    return robot, random_configurations(robot, 1, seed=7)[0]


def test_pinocchio_source_is_crba(chain):
    robot, q = chain
    M = _crba(robot, q)
    source = PinocchioSource(robot)
    assert (source.nv, source.dof_names) == (robot.nv, robot.dof_names)
    np.testing.assert_allclose(source.gim(q), M, rtol=0, atol=1e-14 * np.abs(M).max())
    np.testing.assert_allclose(source.gim_diagonal(q), np.diag(M), rtol=1e-13)
    assert source.diagonal_ratio(q) is None and source.linear_state(q) is None


def test_denoc_sources_are_crba(chain):
    robot, q = chain
    M = _crba(robot, q)
    model = DenocModel.from_urdf(robot.urdf_xml, source=robot.source, joint_order=robot.joint_names)
    lean = DenocDiagonal(PinocchioSource(robot), model.lean())
    np.testing.assert_allclose(lean.gim_diagonal(q), np.diag(M), rtol=1e-12)
    assert lean.diagonal_ratio(q) == pytest.approx(np.diag(M).max() / np.diag(M).min(), rel=1e-12)
    assert lean.lean_model() is not None
    linear = DenocLinear(model)
    np.testing.assert_allclose(linear.gim_diagonal(q), np.diag(M), rtol=1e-12)
    state = GimState(linear, q, lanczos=(0, 1e-12))
    np.testing.assert_allclose(state.udut_pivots, _udut_pivots(M), rtol=1e-10)
    values = np.linalg.eigvalsh(M)
    assert state.extremes == pytest.approx((values[0], values[-1]), rel=1e-9)
    with pytest.raises(Exception, match="never forms"):
        _ = state.M


def test_mujoco_source_is_mj_full_m():
    model = compile_robot(load_robot("ur5"))
    data = mujoco.MjData(model)
    data.qpos[:] = np.random.default_rng(2).uniform(-1.0, 1.0, model.nq)
    mujoco.mj_forward(model, data)
    M = np.empty((model.nv, model.nv))
    mujoco.mj_fullM(model, data, M)
    source = MujocoSource(model, data)
    assert source.reads_state and source.nv == model.nv
    np.testing.assert_array_equal(source.gim(None), M)
    np.testing.assert_array_equal(source.gim_diagonal(None), np.diag(M))
    out = np.empty_like(M)
    assert source.gim_into(None, out) is out and np.array_equal(out, M)
    assert source.diagonal_ratio(None) == pytest.approx(np.diag(M).max() / np.diag(M).min())


def test_given_matrix_is_what_it_holds():
    rng = np.random.default_rng(1)
    A = rng.standard_normal((4, 4))
    M = A @ A.T + 4 * np.eye(4)
    given = GivenMatrix(4)
    given.hold_matrix(M)
    np.testing.assert_array_equal(given.gim(None), M)
    np.testing.assert_array_equal(given.gim_diagonal(None), np.diag(M))
    assert given.diagonal_ratio(None) == np.diag(M).max() / np.diag(M).min()


def test_a_simulation_backend_is_a_source(chain):
    robot, q = chain
    M = _crba(robot, q)
    for name in ("aba", "denoc"):
        backend = make_backend(name, robot, None)
        assert isinstance(backend, MassMatrixSource) and backend.nv == robot.nv
        np.testing.assert_allclose(backend.gim(q), M, rtol=0, atol=1e-12 * np.abs(M).max())
    watch = Watch(robot, ("diagonal_ratio",), source=backend)
    assert watch.lean is backend.lean  # the backend's compiled model serves δ too
    watch.sample(0.0, q)
    assert watch.array("diagonal_ratio")[0] == pytest.approx(
        np.diag(M).max() / np.diag(M).min(), rel=1e-12
    )


class TwoLinkArm(MassMatrixSource):
    """A planar two-link arm's closed-form M(q) (point masses m at the link ends, lengths l):
    a source written by a user, declaring none of the optional paths."""

    nv = 2
    dof_names = ("shoulder", "elbow")

    def __init__(self, m=(1.0, 0.5), l=(1.0, 0.7)):
        self.m, self.l = m, l
        self.calls = 0

    def gim(self, q):
        self.calls += 1
        (m1, m2), (l1, l2) = self.m, self.l
        c2 = math.cos(q[1])
        m11 = (m1 + m2) * l1**2 + m2 * l2**2 + 2 * m2 * l1 * l2 * c2
        m12 = m2 * l2**2 + m2 * l1 * l2 * c2
        return np.array([[m11, m12], [m12, m2 * l2**2]])


def _references(M):
    """Every watchable metric of M that needs no robot, by NumPy."""
    values = np.linalg.eigvalsh(M)
    d = np.diag(M)
    S = M / np.sqrt(np.outer(d, d))
    s_values = np.linalg.eigvalsh(S)
    forward = np.diag(np.linalg.cholesky(M)) ** 2
    backward = _udut_pivots(M)
    return {
        "kappa": values[-1] / values[0],
        "kappa_equilibrated": s_values[-1] / s_values[0],
        "diagonal_ratio": d.max() / d.min(),
        "pivot_ratio_forward": forward.max() / forward.min(),
        "pivot_ratio_backward": backward.max() / backward.min(),
        "eigenvalues": values,
        "diagonal": d,
    }


def test_a_user_written_source_drives_a_watch_for_every_metric_without_a_robot():
    """Every metric that needs neither a robot nor a linear state, from `gim` alone."""
    names = tuple(n for n in METRICS if n not in OPERATOR_METRICS)
    source = TwoLinkArm()
    watch = Watch(metrics=names, source=source)
    assert watch.nv == 2 and watch.dof_names == ("shoulder", "elbow")
    qs = [np.array([0.1, 0.3]), np.array([0.2, 2.9]), np.array([0.0, 0.05])]
    for k, q in enumerate(qs):
        watch.sample(0.1 * k, q)
    arm = TwoLinkArm()
    first = _references(arm.gim(qs[0]))
    alpha = first["kappa"] / first["diagonal_ratio"]
    assert watch.alpha == pytest.approx(alpha, rel=1e-12)
    for k, q in enumerate(qs):
        M = arm.gim(q)
        for name, value in _references(M).items():
            np.testing.assert_allclose(watch.array(name)[k], value, rtol=1e-10, err_msg=name)
        scaled = watch.array("scaled_diagonal_ratio")[k]
        assert scaled == pytest.approx(alpha * _references(M)["diagonal_ratio"], rel=1e-12)
        kappa_1 = np.linalg.cond(M, 1)  # LAPACK's estimate: ‖M⁻¹‖₁ from below, within 3×
        rcond = watch.array("rcond")[k]
        assert 1 / kappa_1 * (1 - 1e-12) <= rcond <= 3 / kappa_1


def test_a_source_declaring_nothing_optional_serves_delta_from_its_m_and_checks_it_once():
    """δ alone: diag M read off `gim` (the default), M checked > 0 at the first sample only."""
    source = TwoLinkArm()
    watch = Watch(metrics=("diagonal_ratio",), source=source)
    for k in range(4):
        watch.sample(float(k), np.array([0.1 * k, 0.4]))
    d = np.diag(TwoLinkArm().gim(np.array([0.3, 0.4])))
    assert watch.array("diagonal_ratio")[-1] == pytest.approx(d.max() / d.min(), rel=1e-14)
    assert source.calls == 4 + 1  # one M per sample's diagonal, one for the first check


def test_a_declared_faster_path_is_taken_and_the_slow_one_is_not():
    """A source that declares δ in one call is asked for it; its M is never formed."""

    class Declared(TwoLinkArm):
        definiteness = "guaranteed"

        def diagonal_ratio(self, q):
            return 2.5

    source = Declared()
    watch = Watch(metrics=("diagonal_ratio",), source=source)
    for k in range(3):
        watch.sample(float(k), np.zeros(2))
    assert list(watch.array("diagonal_ratio")) == [2.5, 2.5, 2.5] and source.calls == 0


def test_a_watch_refuses_what_is_not_a_source():
    from gimwatch.errors import InputError

    with pytest.raises(InputError, match="MassMatrixSource"):
        Watch(metrics=("kappa",), source=object())
    with pytest.raises(InputError, match="kappa_tracked"):
        Watch(metrics=("kappa_tracked",), source=TwoLinkArm())  # it runs RNEA/ABA on a robot


def test_a_metrics_records_are_declared_on_the_metric_not_looked_up_by_name():
    class Counted(Metric):
        """κ, with each sample's count recorded beside it."""

        name = "kappa_counted_for_test"

        def __init__(self):
            self.counts = []

        def __call__(self, state):
            self.counts.append(len(self.counts))
            return evaluate(("kappa",), state)["kappa"]

        def records(self, samples):
            return {"count": np.array(self.counts)} if len(self.counts) == samples else {}

    METRICS[Counted.name] = Counted
    try:
        watch = Watch(metrics=(Counted.name,), source=TwoLinkArm())
        watch.sample(0.0, np.array([0.1, 0.3]))
        watch.sample(0.1, np.array([0.1, 0.4]))
        arrays = watch.arrays()
    finally:
        del METRICS[Counted.name]
    np.testing.assert_array_equal(arrays[f"watch_{Counted.name}_count"], [0, 1])
    M = TwoLinkArm().gim(np.array([0.1, 0.4]))
    assert arrays[f"watch_{Counted.name}"][1] == pytest.approx(np.linalg.cond(M), rel=1e-10)
