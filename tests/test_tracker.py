"""The κ tracker against dense eigen-solves (NumPy, Pinocchio's M⁻¹, mpmath) along trajectories."""

import dataclasses
from pathlib import Path

import mpmath
import numpy as np
import pinocchio as pin
import pytest
from threadpoolctl import threadpool_limits

from gimwatch.crosscheck import denoc_model
from gimwatch.denoc import DenocModel
from gimwatch.errors import ConditioningError
from gimwatch.metrics.tracker import KappaTracker, TrackerSettings, track_kappa
from gimwatch.metrics.tracker.providers import PinocchioProducts
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import load_robot
from gimwatch.simulation.scene import load_scene, parse_scene
from gimwatch.simulation.simulate import run_scene
from gimwatch.stress.reference_planar import PlanarChainReference

SCENES = Path(__file__).resolve().parents[1] / "gimwatch" / "scenes"
#: The documented tracker rtol is 1e-10 per end (KappaTracker's default; κ to about 2e-10):
#: κ and each end are held to 5e-10, a margin of 2.5 on κ's 2e-10 (5 on an end's 1e-10) for the
#: reference's own round-off (at most eps·κ ≈ 1.5e-10 for eigvalsh's λmin at κ = 6.7e5, the
#: largest κ compared that way; measured tracker errors 1e-11 to 1.1e-10).
DOCUMENTED_RTOL_MARGIN = 5e-10


def _paper_trajectory(n: int) -> np.ndarray:
    """q at every sample of the paper's swinging chain scene (δ watched only: cheap)."""
    scene = load_scene(SCENES / f"chain_{n}.toml")
    watch = dataclasses.replace(
        scene.watch, metrics=("diagonal_ratio",), alarm_metric=None, alarm_threshold=None
    )
    return run_scene(dataclasses.replace(scene, watch=watch)).q


def _swinging(n: int, duration: float, sample: float) -> np.ndarray:
    scene = parse_scene(
        {
            "robot": f"chain:{n}",
            "duration": duration,
            "sample": sample,
            "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
            "integrator": {"method": "RK4", "dt": 1e-3},
            "dynamics": {"backend": "denoc"},
            "watch": {"metrics": ["diagonal_ratio"]},
        },
        source=f"<swinging chain:{n}>",
    )
    return run_scene(scene).q


@pytest.mark.parametrize("n", [4, 10, 20])
def test_tracker_matches_dense_kappa_along_the_paper_trajectories(n):
    robot = load_robot(f"chain:{n}")
    data = robot.new_data()
    qs = _paper_trajectory(n)
    results = track_kappa(denoc_model(robot).lean(), qs)
    with threadpool_limits(1, "blas"):
        dense = np.array([np.linalg.eigvalsh(pin.crba(robot.model, data, q))[[0, -1]] for q in qs])
    kappa = dense[:, 1] / dense[:, 0]
    tracked = np.array([r.kappa for r in results])
    error = np.abs(tracked - kappa) / kappa
    assert error.max() <= DOCUMENTED_RTOL_MARGIN, (
        f"max relative error {error.max():.2e} at sample {error.argmax()}"
    )
    assert len(results) == len(qs) > 400
    assert results[0].fallback == "start"
    warm = [r for r in results[1:] if r.fallback == ""]
    assert len(warm) >= 0.95 * (len(results) - 1)  # the warm start is the rule
    # products per sample are reported and add up
    assert all(r.products == r.products_max + r.products_min > 0 for r in results)
    # shift-invert separates λmin: a warm sample takes one factor and a handful of products
    assert np.median([r.products for r in warm]) <= 10
    # the shifted factor and the two certificates (λmin, λmax)
    assert np.median([r.factors for r in warm]) == 3


def test_tracker_matches_mpmath_on_a_50_link_chain():
    """κ ≈ 2.5e7: float64's eigvalsh loses λmin's digits (eps·κ ≈ 6e-9); mpmath does not.

    Held to the documented rtol with its margin (5e-10, below κ·eps); measured 4.0e-11.
    """
    n = 50
    qs = _swinging(n, 0.3, 0.1)
    lean = DenocModel.from_chain(chain_spec(n)).lean()
    results = track_kappa(lean, qs)
    reference = PlanarChainReference(chain_spec(n), dps=30)
    for q, result in zip(qs[::2], results[::2], strict=True):
        with mpmath.workdps(30):
            values = mpmath.eigsy(reference.gim(q), eigvals_only=True)
            values = sorted(float(x) for x in values)
        kappa = values[-1] / values[0]
        assert abs(result.kappa - kappa) / kappa <= DOCUMENTED_RTOL_MARGIN, (result.kappa, kappa)


def test_tracker_matches_dense_along_a_200_link_swinging_chain():
    """λmax against eigvalsh of CRBA's M, λmin against eigvalsh of Pinocchio's M⁻¹.

    κ ≈ 6e9: the dense λmin of M carries eps·κ ≈ 1e-6 relative error, the largest
    eigenvalue of M⁻¹ (computeMinverse) only about eps, so both ends are compared where
    float64 resolves them.
    """
    n = 200
    robot = load_robot(f"chain:{n}")
    data = robot.new_data()
    qs = _swinging(n, 0.4, 0.05)
    tracker = KappaTracker(denoc_model(robot).lean(), robot.nv)
    with threadpool_limits(1, "blas"):
        for q in qs:
            result = tracker.sample(q)
            top = np.linalg.eigvalsh(pin.crba(robot.model, data, q))[-1]
            inverse = np.linalg.eigvalsh(pin.computeMinverse(robot.model, data, q))[-1]
            kappa = top * inverse
            assert abs(result.kappa - kappa) / kappa <= DOCUMENTED_RTOL_MARGIN, (
                result.kappa,
                kappa,
            )
            assert abs(result.lambda_max - top) / top <= DOCUMENTED_RTOL_MARGIN
            assert abs(result.lambda_min * inverse - 1) <= DOCUMENTED_RTOL_MARGIN
    assert result.kappa > 1e9


def test_lambda_min_falling_below_the_shift_is_detected_and_refactored():
    """λmin drops 7 % between two samples (straight chain, then bent): the first shift
    σ = λmin(previous)·(1 − s) lies above the new λmin, a pivot of M − σ·1 is not positive,
    and the tracker widens s and refactors instead of trusting the factor."""
    robot = load_robot("chain:10")
    data = robot.new_data()
    tracker = KappaTracker(denoc_model(robot).lean(), robot.nv)
    for q in (np.full(10, 0.3), np.full(10, 0.3) + 1e-3, np.zeros(10), np.zeros(10) + 1e-3):
        result = tracker.sample(q)
        values = np.linalg.eigvalsh(pin.crba(robot.model, data, q))
        assert result.kappa == pytest.approx(values[-1] / values[0], rel=DOCUMENTED_RTOL_MARGIN)
        assert result.lambda_min == pytest.approx(values[0], rel=DOCUMENTED_RTOL_MARGIN)
        # every sample adds two factors: the certificates that no eigenvalue lies below λmin
        # and none above λmax
        if q[0] == 0.0:  # the drop: refactored; right after it: one factor again
            assert result.factors == 2 + 2, result
        elif q[0] == 1e-3:
            assert result.factors == 1 + 2, result


def test_compiled_path_recovers_from_a_jump_by_a_cold_start():
    """λmax falls 14× between two samples (bent chain, then curled): the warm result moved
    beyond the jump rule, the sample is redone cold (reported), and the next is warm again."""
    robot = load_robot("chain:10")
    data = robot.new_data()
    tracker = KappaTracker(denoc_model(robot).lean(), robot.nv)
    fallbacks = []
    for q in (np.full(10, 0.3), np.full(10, 0.301), np.full(10, 1.0), np.full(10, 1.001)):
        result = tracker.sample(q)
        values = np.linalg.eigvalsh(pin.crba(robot.model, data, q))
        assert result.kappa == pytest.approx(values[-1] / values[0], rel=DOCUMENTED_RTOL_MARGIN)
        fallbacks.append(result.fallback)
    assert fallbacks == ["start", "", "cold", ""]
    # the eigenvectors carried over: a Ritz residual ‖r‖ ~ sqrt(rtol · θ · gap) gives θ to rtol
    top, low = tracker.eigenvectors()
    M = pin.crba(robot.model, data, np.full(10, 1.001))
    assert np.linalg.norm(M @ top - (top @ M @ top) * top) <= 1e-4 * np.linalg.norm(M)
    assert abs(low @ np.linalg.eigh(M)[1][:, 0]) == pytest.approx(1.0, abs=1e-8)


def test_tracker_leaves_the_lean_model_configuration_alone():
    """The tracker factors M − σ·1 in its own buffers: a LeanModel configured by its owner
    (a simulation backend, the watch) still solves with M(q) of the owner's q."""
    robot = load_robot("chain:8")
    lean = denoc_model(robot).lean()
    q = np.linspace(-0.5, 0.5, 8)
    lean.configure(q)
    tracker = KappaTracker(lean, robot.nv)
    tracker.sample(np.full(8, 0.4))
    tracker.sample(np.full(8, 0.41))
    y = np.arange(1.0, 9.0)
    M = pin.crba(robot.model, robot.new_data(), q)
    np.testing.assert_allclose(lean.gim_solve(y), np.linalg.solve(M, y), rtol=1e-10)


def test_pinocchio_products_give_the_same_kappa():
    robot = load_robot("ur5")
    qs = np.linspace(0.0, 1.0, 5)[:, None] * np.linspace(-1, 1, robot.nq)[None, :]
    ours = track_kappa(denoc_model(robot).lean(), qs)
    theirs = track_kappa(PinocchioProducts(robot), qs)
    for q, a, b in zip(qs, ours, theirs, strict=True):
        # each against LAPACK on CRBA's M (κ ≈ 1e2 here: eigvalsh resolves it to ~1e-14)
        values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), q))
        kappa = values[-1] / values[0]
        assert a.kappa == pytest.approx(kappa, rel=DOCUMENTED_RTOL_MARGIN)
        assert b.kappa == pytest.approx(kappa, rel=DOCUMENTED_RTOL_MARGIN)


class _Diagonalised:
    """M(t) = Q diag(λ(t)) Qᵀ with a chosen spectrum: the products, and the dense matrix."""

    def __init__(self, n: int, seed: int = 0) -> None:
        self.nv = n
        self.Q = np.linalg.qr(np.random.default_rng(seed).standard_normal((n, n)))[0]
        self.values = np.ones(n)

    def matrix(self, values) -> np.ndarray:
        return (self.Q * values) @ self.Q.T

    def configure(self, values) -> None:
        self.M = self.matrix(values)
        self.Minv = (self.Q / values) @ self.Q.T

    def gim_product(self, x):
        return self.M @ x

    def gim_solve(self, y):
        return self.Minv @ y


def _spectrum(n: int, top: float, second: float, low: float) -> np.ndarray:
    values = np.linspace(2.0, 5.0, n)
    values[-1], values[-2], values[0] = top, second, low
    return values


def test_eigenvalue_crossing_is_tracked():
    """The two leading eigenvalues swap (their eigenvectors too): Rayleigh–Ritz on the block."""
    n = 60
    op = _Diagonalised(n)
    tracker = KappaTracker(op, n, TrackerSettings(rtol=1e-12))
    for t in np.linspace(0.0, 1.0, 11):
        values = _spectrum(n, 10.0 + t, 11.0 - t, 0.5)  # cross at t = 0.5
        result = tracker.sample(values)
        expected = values.max() / values.min()
        assert result.kappa == pytest.approx(expected, rel=5e-12)  # rtol 1e-12 per end, margin 2.5


def test_sudden_jump_is_detected_and_recovered():
    """A new leading eigenvalue far above the tracked one, along an eigenvector the warm
    block is orthogonal to: the warm start cannot see it; the probe's residual and the jump
    rule send the sample to the cold start, which finds it."""
    n = 80
    op = _Diagonalised(n)
    tracker = KappaTracker(op, n)
    values = _spectrum(n, 10.0, 9.0, 0.5)
    for _ in range(3):
        assert tracker.sample(values).fallback in ("", "start")
    jumped = values.copy()
    jumped[5] = 1000.0  # eigenvector Q[:, 5]: orthogonal to the tracked ones
    result = tracker.sample(jumped)
    assert result.fallback == "cold"
    assert result.kappa == pytest.approx(1000.0 / 0.5, rel=DOCUMENTED_RTOL_MARGIN)
    assert tracker.sample(jumped).fallback == ""  # warm again afterwards


def test_dense_fallback_when_the_cold_start_cannot_converge():
    n = 40
    op = _Diagonalised(n)
    values = _spectrum(n, 10.0, 9.0, 0.5)
    tracker = KappaTracker(
        op, n, TrackerSettings(warm_products=2, max_products=3), dense=lambda v: op.matrix(v)
    )
    result = tracker.sample(values)
    assert result.fallback == "dense"
    assert result.kappa == pytest.approx(20.0, rel=1e-12)
    without = KappaTracker(op, n, TrackerSettings(warm_products=2, max_products=3))
    with pytest.raises(ConditioningError, match="did not converge in 3 products"):
        without.sample(values)


def _dense_kappa(robot, q) -> float:
    """κ by LAPACK on Pinocchio's CRBA: neither the tracker nor the watch's own κ."""
    values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), q))
    return values[-1] / values[0]


@pytest.mark.parametrize("backend", ["aba", "denoc"])
def test_watch_metric_kappa_tracked_is_the_dense_kappa(backend):
    """The watch's tracked κ along a simulation, at every saved q (κ ≈ 1e3: eigvalsh resolves
    it to ~1e-13), and equal to the watch's dense κ computed beside it."""
    table = {
        "robot": "chain:6",
        "duration": 0.5,
        "sample": 0.05,
        "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
        "integrator": {"method": "RK4", "dt": 0.01},
        "dynamics": {"backend": backend},
        "watch": {"metrics": ["kappa", "kappa_tracked"]},
    }
    run = run_scene(parse_scene(table, source="t.toml"))
    robot = load_robot("chain:6")
    reference = [_dense_kappa(robot, q) for q in run.q]
    assert len(reference) == 11
    tracked = run.watch["watch_kappa_tracked"]
    np.testing.assert_allclose(tracked, reference, rtol=DOCUMENTED_RTOL_MARGIN, atol=0)
    # the dense κ beside it: eps·κ ≈ 2e-13 on DeNOC's M (the denoc backend), measured 2e-13
    np.testing.assert_allclose(run.watch["watch_kappa"], reference, rtol=1e-11, atol=0)


def test_watch_metric_on_a_floating_base_uses_the_compiled_products():
    from gimwatch.watch.watch import Watch

    robot = load_robot("solo12", floating=True)
    watch = Watch(robot, ("kappa", "kappa_tracked"))
    q = pin.neutral(robot.model)
    reference = []
    for k in range(3):
        q = q.copy()
        q[7:] += 0.05 * k
        watch.sample(0.1 * k, q)
        reference.append(_dense_kappa(robot, q))
    np.testing.assert_allclose(
        watch.series["kappa_tracked"], reference, rtol=DOCUMENTED_RTOL_MARGIN, atol=0
    )
    assert all(p > 0 for p in watch.metrics["kappa_tracked"].products)
