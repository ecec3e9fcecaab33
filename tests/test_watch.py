import numpy as np
import numpy.linalg
import pinocchio as pin
import pytest
import scipy.linalg
from conftest import planar_rod_chain_gim

from gimwatch.metrics.registry import KappaLanczos
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene
from gimwatch.watch.watch import METRICS, Watch, estimator_quality

ALL = (
    "kappa",
    "diagonal_ratio",
    "scaled_diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "rcond",
    "eigenvalues",
    "diagonal",
)


def test_every_metric_matches_the_closed_form_gim():
    robot = load_robot("chain:5")
    qs = random_configurations(robot, 3, seed=7)
    watch = Watch(robot, ALL)
    for k, q in enumerate(qs):
        watch.sample(0.1 * k, q)
    M0 = planar_rod_chain_gim(qs[0], 2.2, 1.0)
    for k, q in enumerate(qs):
        M = planar_rod_chain_gim(q, 2.2, 1.0)
        lam = np.linalg.eigvalsh(M)
        d = np.diag(M)
        L = np.linalg.cholesky(M)
        U = np.linalg.cholesky(M[::-1, ::-1])
        fwd, bwd = np.diag(L) ** 2, np.diag(U) ** 2
        alpha = (np.linalg.cond(M0)) / (np.diag(M0).max() / np.diag(M0).min())
        expected = {
            "kappa": lam[-1] / lam[0],
            "diagonal_ratio": d.max() / d.min(),
            "scaled_diagonal_ratio": alpha * d.max() / d.min(),
            "pivot_ratio_forward": fwd.max() / fwd.min(),
            "pivot_ratio_backward": bwd.max() / bwd.min(),
        }
        for name, value in expected.items():
            assert watch.series[name][k] == pytest.approx(value, rel=1e-9), name
        np.testing.assert_allclose(watch.series["eigenvalues"][k], lam, rtol=1e-9)
        np.testing.assert_allclose(watch.series["diagonal"][k], d, rtol=1e-12)
        kappa1 = np.linalg.cond(M, 1)
        rcond = watch.series["rcond"][k]
        assert (
            1 / kappa1 <= rcond * (1 + 1e-9) and rcond <= 3 / kappa1
        )  # dpocon lower-bounds kappa_1


def test_metric_registry_is_the_scene_vocabulary():
    from gimwatch.simulation.scene import METRIC_NAMES

    assert tuple(METRICS) == METRIC_NAMES


@pytest.fixture
def counters(monkeypatch):
    counts = {"eig": 0, "crba": 0, "diag": 0}
    from gimwatch.watch import kernels

    for kernel in (
        kernels.scaled_spectrum,
        kernels.spectrum_ratio,
        kernels.spectrum_scale,
    ):  # compiled before the
        kernel(np.eye(2))  # patch below, which numba would otherwise see in its place

    def wrap(module, name, key):
        original = getattr(module, name)

        def counting(*args, **kwargs):
            # Eigen-solves of 3x3 link inertias (URDF checks at load time) are not GIM work.
            if key != "eig" or numpy.shape(args[0]) != (3, 3):
                counts[key] += 1
            return original(*args, **kwargs)

        monkeypatch.setattr(module, name, counting)

    for name in ("eigvalsh", "eigh", "eig", "eigvals"):
        wrap(scipy.linalg, name, "eig")
        wrap(numpy.linalg, name, "eig")
    wrap(pin, "crba", "crba")
    wrap(pin, "computeCentroidalMap", "diag")
    wrap(kernels, "scaled_spectrum", "eig")  # the watch's compiled eigen-solve
    from gimwatch.denoc.lean import LeanModel

    wrap(LeanModel, "gim_diagonal", "diag")  # the watch's compiled O(n) diagonal
    wrap(LeanModel, "diagonal_ratio", "diag")  # … and δ from it in the same call
    return counts


def _run(metrics):
    table = {
        "robot": "chain:6",
        "duration": 0.5,
        "sample": 0.05,
        "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
        "integrator": {"method": "RK4", "dt": 0.01},
        "watch": {"metrics": list(metrics)},
    }
    return run_scene(parse_scene(table, source="t.toml"))


def test_without_kappa_there_is_no_eigen_solve_and_no_mass_matrix(counters):
    run = _run(["diagonal_ratio"])
    assert run.t.size == 11 and run.watch["watch_diagonal_ratio"].size == 11
    assert counters == {"eig": 0, "crba": 0, "diag": 11}


def test_scaled_ratio_costs_one_eigen_solve_at_t0_only(counters):
    _run(["scaled_diagonal_ratio"])
    # t0 forms M to calibrate α and reads diag M off it; the 10 later samples take O(n) δ
    assert counters == {"eig": 1, "crba": 1, "diag": 10}


def test_kappa_costs_one_eigen_solve_per_sample(counters):
    _run(["kappa", "diagonal_ratio", "eigenvalues"])  # they share one solve per sample
    assert counters == {"eig": 11, "crba": 11, "diag": 0}


def test_nothing_watched_costs_nothing(counters):
    run = _run([])
    assert counters == {"eig": 0, "crba": 0, "diag": 0} and run.watch == {}


def test_alarm_is_raised_on_upward_crossings_only():
    robot = load_robot("chain:3")
    watch = Watch(robot, ("diagonal_ratio",), alarm_metric="diagonal_ratio", alarm_threshold=20.0)
    straight, bent = np.zeros(3), np.array([0.0, 0.0, 2.5])
    # straight: delta = 27 > 20; bent tip: M_33 same, M_11 smaller -> below
    raised = [
        watch.sample(t, q) is not None for t, q in enumerate([straight, straight, bent, straight])
    ]
    assert raised == [True, False, False, True]
    assert [a.time_s for a in watch.alarms] == [0.0, 3.0]


def test_estimator_quality_uses_alpha_from_t0_only():
    kappa = np.array([100.0, 200.0, 400.0, 300.0])
    delta = np.array([10.0, 25.0, 40.0, 20.0])
    quality = estimator_quality(kappa, delta)
    assert quality.alpha == 10.0
    errors = (np.abs(10 * delta - kappa) / kappa)[1:]  # after t0, where αδ = κ by construction
    assert quality.median_relative_error == pytest.approx(np.median(errors))
    assert quality.max_relative_error == pytest.approx(1 / 3)
    assert quality.spearman == pytest.approx(0.8)
    assert quality.pearson_log == pytest.approx(np.corrcoef(np.log(delta), np.log(kappa))[0, 1])


def test_kappa_lanczos_tracks_the_closed_form_kappa_without_forming_m(counters):
    run = _run(["kappa_lanczos"])
    assert counters == {"eig": 0, "crba": 0, "diag": 0}  # matrix-free: no M, no dense solve
    for q, value in zip(run.q, run.watch["watch_kappa_lanczos"], strict=True):
        lam = np.linalg.eigvalsh(planar_rod_chain_gim(q, 2.2, 1.0))
        # ARPACK at TOL = 1e-3 on each eigenvalue: κ within 2e-3 (measured 1e-13 here)
        assert value == pytest.approx(lam[-1] / lam[0], rel=2e-3)


def test_kappa_lanczos_on_a_sixty_link_straight_chain_is_accurate():
    # beyond the engine's basis (24 < n): the κ tracker at the watch's TOL = 1e-3 certifies each
    # end (Sylvester), so the true κ lies in [κ, κ·(1 + 2·TOL/(1 − TOL))]; measured 3.1e-5 below
    # numpy's κ of the closed-form M (ARPACK, the former engine, happened to reach 5e-8)
    n = 60
    watch = Watch(load_robot(f"chain:{n}"), ("kappa_lanczos",))
    q = np.zeros(n)
    watch.sample(0.0, q)
    lam = np.linalg.eigvalsh(planar_rod_chain_gim(q, 2.2, 1.0))
    value, exact, tol = watch.series["kappa_lanczos"][0], lam[-1] / lam[0], KappaLanczos.TOL
    assert value * (1 - 1e-12) <= exact <= value * (1 + 2 * tol / (1 - tol))


@pytest.mark.parametrize("nv", [3, 32, 33, 40, 101])
def test_matrix_watch_spectrum_matches_numpy_scaled_or_not(nv):
    rng = numpy.random.default_rng(nv)
    A = rng.standard_normal((nv, nv))
    M = A @ A.T + 1e-3 * numpy.eye(nv)
    reference = numpy.linalg.eigvalsh(M)
    watch = Watch.from_matrices(nv, ("kappa", "eigenvalues", "diagonal_ratio", "diagonal"))
    kappa_only = Watch.from_matrices(nv, ("kappa",))
    for t, scale in enumerate((1.0, 2.0**-900, 2.0**900, 1e-300, 1e300)):
        watch.sample_matrix(t, M * scale)
        kappa_only.sample_matrix(t, M * scale)
    kappa = reference[-1] / reference[0]
    numpy.testing.assert_allclose(watch.array("kappa"), kappa, rtol=1e-9)
    numpy.testing.assert_allclose(kappa_only.array("kappa"), kappa, rtol=1e-9)
    numpy.testing.assert_allclose(watch.array("eigenvalues")[0], reference, rtol=1e-9)
    d = numpy.diag(M)
    numpy.testing.assert_allclose(watch.array("diagonal_ratio"), d.max() / d.min(), rtol=1e-14)
    numpy.testing.assert_allclose(watch.array("diagonal")[0], d, rtol=0)


def test_a_watch_on_a_chain_too_long_for_pinocchios_data_runs_on_denoc():
    """chain:600 (Data would need GBs): δ from DeNOC against the closed-form rod chain's M."""
    from closed_forms import rod_chain_gim

    robot = load_robot("chain:600")
    watch = Watch(robot, ("diagonal_ratio",))
    assert watch.data is None
    q = np.random.default_rng(3).uniform(-0.5, 0.5, 600)
    watch.sample(0.0, q)
    diagonal = np.diag(rod_chain_gim(q))
    expected = diagonal.max() / diagonal.min()
    assert watch.arrays()["watch_diagonal_ratio"][0] == pytest.approx(expected, rel=1e-12)
