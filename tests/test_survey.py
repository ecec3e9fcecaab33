import numpy as np
import pytest
from conftest import EXAMPLE_ROBOTS, NO_DOF_WHEN_FIXED, SINGULAR_GIM, planar_rod_chain_gim

from gimwatch.crosscheck import denoc_model
from gimwatch.model.robot_spec import default_floating
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.survey.run import DOF_METRICS, METRICS, run_survey, sample_metrics
from gimwatch.survey.trajectory import FLOATING_REASON, TrajectorySettings

SPECS = ["chain:4", "ur5", "cassie", "bravo7_gripper", "hector"]
RUNS = TrajectorySettings(count=2, duration_s=0.2, sample_s=0.02)


@pytest.fixture(scope="module")
def serial():
    return run_survey(SPECS, samples=12, seed=3, chunk_size=5, workers=1, trajectories=RUNS)


def _same(a, b):
    assert [r.name for r in a.robots] == [r.name for r in b.robots]
    assert a.failures == b.failures
    for x, y in zip(a.robots, b.robots, strict=True):
        np.testing.assert_array_equal(x.sample_index, y.sample_index)
        for key in METRICS + DOF_METRICS:
            np.testing.assert_array_equal(x.metrics[key], y.metrics[key], err_msg=f"{x.name} {key}")
        assert x.alpha == y.alpha and x.worst == y.worst
        assert (x.trajectories is None) == (y.trajectories is None)
        if x.trajectories is None:
            continue
        assert x.trajectories.skipped == y.trajectories.skipped
        assert len(x.trajectories.runs) == len(y.trajectories.runs)
        for u, w in zip(x.trajectories.runs, y.trajectories.runs, strict=True):
            assert (u.start_sample, u.status, u.steps) == (w.start_sample, w.status, w.steps)
            for key in ("t", "q", "kappa", "diagonal_ratio", "scaled_diagonal_ratio"):
                np.testing.assert_array_equal(getattr(u, key), getattr(w, key), err_msg=key)


def test_chain_metrics_match_the_closed_form_rod_gim():
    robot = load_robot("chain:4")
    qs = random_configurations(robot, 6, seed=1)
    metrics = sample_metrics(robot, qs)
    for row, q in enumerate(qs):
        M = planar_rod_chain_gim(q, 2.2, 1.0)
        values, vectors = np.linalg.eigh(M)
        assert metrics["kappa"][row] == pytest.approx(values[-1] / values[0], rel=1e-9)
        assert metrics["diagonal_ratio"][row] == pytest.approx(np.diag(M).max() / np.diag(M).min())
        assert metrics["lambda_min_dof"][row] == np.argmax(np.abs(vectors[:, 0]))
        assert metrics["lambda_max_dof"][row] == np.argmax(np.abs(vectors[:, -1]))
        assert metrics["min_diagonal_dof"][row] == np.argmin(np.diag(M))


def test_metrics_agree_with_analyze_on_a_real_robot():
    robot = load_robot("panda")
    qs = random_configurations(robot, 4, seed=2)
    metrics = sample_metrics(robot, qs)
    for row, q in enumerate(qs):
        # numpy on DeNOC's M (its own recursions, not Pinocchio's CRBA nor gimwatch.metrics)
        M = denoc_model(robot).gim(q)
        values = np.linalg.eigvalsh(M)
        forward = np.diag(np.linalg.cholesky(M)) ** 2
        backward = np.diag(np.linalg.cholesky(M[::-1, ::-1])) ** 2
        for key, value in [
            ("kappa", values[-1] / values[0]),
            ("diagonal_ratio", np.diag(M).max() / np.diag(M).min()),
            ("pivot_ratio_forward", forward.max() / forward.min()),
            ("pivot_ratio_backward", backward.max() / backward.min()),
            ("lambda_min", values[0]),
        ]:
            assert metrics[key][row] == pytest.approx(value, rel=1e-9), key
        assert metrics["max_diagonal_dof"][row] == np.argmax(np.diag(M))


def test_paper_chain_is_calibrated_at_the_straight_neutral_configuration(serial):
    chain = serial.robots[0]
    assert chain.name == "chain_4" and chain.samples == 13
    # Shah & Saha (2013), Eq. (7)-(8): kappa = 1074.44, delta = 64 for the straight chain
    assert chain.metrics["kappa"][0] == pytest.approx(1074.44, abs=0.01)
    assert chain.alpha == pytest.approx(1074.44 / 64, abs=1e-3)
    assert chain.worst[0].sample == 0 and chain.worst[0].q == (0.0, 0.0, 0.0, 0.0)
    assert chain.extreme_dofs["min_diagonal_dof"] == ("joint_4", 1.0)


def test_statistics_recomputed_independently(serial):
    for r in serial.robots:
        kappa, delta = r.metrics["kappa"], r.metrics["diagonal_ratio"]
        assert np.all(kappa >= delta * (1 - 1e-12))  # lambda_min <= M_ii <= lambda_max
        assert r.quantiles["kappa"]["max"] == kappa.max()
        assert r.quantiles["diagonal_ratio"]["median"] == pytest.approx(np.median(delta))
        error = np.abs(kappa[0] / delta[0] * delta[1:] - kappa[1:]) / kappa[1:]
        assert r.alpha_delta_rel_error_median == pytest.approx(np.median(error), rel=1e-12)
        assert r.alpha_delta_rel_error_max == pytest.approx(error.max(), rel=1e-12)
        if np.ptp(kappa) == 0:  # hector: a free-flyer alone, M is constant in the body frame
            assert np.isnan(r.pearson_log) and np.isnan(r.spearman)
            continue
        assert r.pearson_log == pytest.approx(np.corrcoef(np.log(delta), np.log(kappa))[0, 1])
        ranks = [np.argsort(np.argsort(x)) for x in (delta, kappa)]
        assert r.spearman == pytest.approx(np.corrcoef(*ranks)[0, 1])


def test_failures_are_reported_and_the_survey_goes_on(serial):
    assert [r.name for r in serial.robots] == ["chain_4", "ur5", "hector"]
    hector = serial.robots[2]
    assert hector.floating and hector.note == "" and hector.nv == 6  # the loader's free-flyer
    failures = {f.spec: (f.stage, f.reason) for f in serial.failures}
    assert failures["cassie"] == (
        "load",
        "robot 'cassie': example-robot-data ships it only as SDF; gimwatch reads URDF",
    )
    stage, reason = failures["bravo7_gripper"]
    assert stage == "gim" and "is singular" in reason and "bravo_finger1_joint" in reason


def test_process_pool_gives_identical_results(serial):
    """Regression test: two worker processes reproduce the serial survey bit for bit (the
    serial values are held against NumPy in the closed-form and recomputation tests)."""
    result = run_survey(SPECS, samples=12, seed=3, chunk_size=5, workers=2, trajectories=RUNS)
    _same(result, serial)


def test_dask_local_cluster_gives_identical_results(serial):
    """Regression test: a Dask cluster reproduces the serial survey bit for bit."""
    from distributed import LocalCluster  # the `dask` extra, also in the `test` extra

    with LocalCluster(
        n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None
    ) as cluster:
        result = run_survey(
            SPECS,
            samples=12,
            seed=3,
            chunk_size=5,
            scheduler=cluster.scheduler_address,
            trajectories=RUNS,
        )
    _same(result, serial)


def test_ctrl_c_keeps_the_finished_chunks():
    def progress(finished, total):
        assert total == 6  # two robots x 13 samples in chunks of 5
        if finished == 2:
            raise KeyboardInterrupt

    result = run_survey(["ur5", "panda"], samples=12, chunk_size=5, workers=1, progress=progress)
    assert result.interrupted and result.not_reached == ("panda",)
    (ur5,) = result.robots
    np.testing.assert_array_equal(ur5.sample_index, np.arange(10))
    assert np.isfinite(ur5.alpha)


def test_seed_changes_the_samples_but_not_the_neutral_one(serial):
    other = run_survey(["ur5"], samples=12, seed=4, workers=1)
    assert other.robots[0].metrics["kappa"][0] == serial.robots[1].metrics["kappa"][0]
    assert not np.array_equal(other.robots[0].metrics["kappa"], serial.robots[1].metrics["kappa"])


@pytest.mark.parametrize("name", EXAMPLE_ROBOTS)
def test_every_example_robot_is_surveyed_or_explained(name):
    result = run_survey([name], samples=2, workers=1)
    if name in SINGULAR_GIM:
        assert result.robots == () and result.failures[0].stage == "gim"
        return
    (robot,) = result.robots
    expected = name in NO_DOF_WHEN_FIXED or default_floating(name)  # example-robot-data's base
    assert robot.floating == expected and robot.samples == 3
    assert np.all(np.isfinite(robot.metrics["kappa"]))


def _independent_run_statistics(robot, run):
    """κ, δ at every sampled q from numpy on DeNOC's M, then α, errors, correlations."""
    model = denoc_model(robot)
    gims = [model.gim(q) for q in run.q]
    kappa = np.array([(lambda w: w[-1] / w[0])(np.linalg.eigvalsh(M)) for M in gims])
    delta = np.array([np.diag(M).max() / np.diag(M).min() for M in gims])
    alpha = kappa[0] / delta[0]  # calibrated at t0 of the run (Eq. 15)
    error = np.abs(alpha * delta[1:] - kappa[1:]) / kappa[1:]
    pearson = np.corrcoef(np.log(delta), np.log(kappa))[0, 1]
    ranks = [np.argsort(np.argsort(x)) for x in (delta, kappa)]
    return kappa, delta, alpha, error, pearson, np.corrcoef(*ranks)[0, 1]


def test_trajectory_statistics_match_an_independent_recomputation(serial):
    for r in serial.robots[:2]:  # chain_4, ur5
        robot = load_robot(r.spec)
        stats = r.trajectories
        assert len(stats.completed) == 2 and stats.skipped == "" and stats.errors == ()
        qs = random_configurations(robot, 12, seed=3)
        errors, pearsons = [], []
        for k, run in enumerate(stats.runs):
            assert run.start_sample == k + 1 and run.method == "DOP853"
            np.testing.assert_array_equal(run.q[0], qs[k])  # starts at random sample k + 1
            np.testing.assert_allclose(run.t, np.arange(11) * 0.02, atol=1e-12)
            assert np.ptp(run.q, axis=0).max() > 1e-3  # it moved
            kappa, delta, alpha, error, pearson, spearman = _independent_run_statistics(robot, run)
            np.testing.assert_allclose(run.kappa, kappa, rtol=1e-9)
            np.testing.assert_allclose(run.diagonal_ratio, delta, rtol=1e-12)
            np.testing.assert_allclose(run.scaled_diagonal_ratio, alpha * delta, rtol=1e-9)
            assert run.alpha == pytest.approx(alpha, rel=1e-9)
            assert run.alpha_delta_rel_error_median == pytest.approx(np.median(error), abs=1e-9)
            assert run.pearson_log == pytest.approx(pearson, rel=1e-9)
            assert run.spearman == pytest.approx(spearman, rel=1e-9)
            errors.append(error)
            pearsons.append(pearson)
        pooled = np.concatenate(errors)
        assert stats.alpha_delta_rel_error_median == pytest.approx(np.median(pooled), abs=1e-9)
        assert stats.alpha_delta_rel_error_max == pytest.approx(pooled.max(), abs=1e-9)
        assert stats.pearson_log_median == pytest.approx(np.median(pearsons), rel=1e-9)
        assert stats.pearson_log_min == pytest.approx(min(pearsons), rel=1e-9)


def test_floating_robots_are_not_simulated_and_say_why(serial):
    hector = serial.robots[2].trajectories
    assert hector.runs == () and hector.skipped == FLOATING_REASON
    assert np.isnan(hector.pearson_log_median)


def test_continuous_joints_use_rk4_and_a_stiff_run_stops_at_the_step_budget():
    settings = TrajectorySettings(count=1, duration_s=0.1, sample_s=0.01)
    (kinova,) = run_survey(["kinova"], samples=1, workers=1, trajectories=settings).robots
    (run,) = kinova.trajectories.runs
    assert run.method == "RK4" and run.status == "completed" and run.steps == 100
    robot = load_robot("kinova")
    kappa, delta, *_ = _independent_run_statistics(robot, run)
    np.testing.assert_allclose(run.kappa, kappa, rtol=1e-9)
    np.testing.assert_allclose(run.diagonal_ratio, delta, rtol=1e-12)
    budget = TrajectorySettings(count=1, duration_s=0.1, sample_s=0.01, max_steps=30)
    (capped,) = run_survey(["kinova"], samples=1, workers=1, trajectories=budget).robots
    (run,) = capped.trajectories.runs
    assert run.status == "step-budget" and run.steps == 30 and run.t[-1] == pytest.approx(0.03)
    assert capped.trajectories.completed == () and np.isnan(
        capped.trajectories.alpha_delta_rel_error_median
    )
