"""The O(n) DeNOC path: compiled recursions, matrix-free κ, long-chain analysis and simulation.

References: Pinocchio (CRBA, RNEA, ABA, Cholesky), the URDF read by yourdfpy, the mpmath
planar-chain reference, and the straight-chain closed forms δ = n³ and κ ≈ 4n⁴.
"""

import mpmath
import numpy as np
import pinocchio as pin
import pytest
from closed_forms import rod_chain_gim, straight_chain_extreme_eigenvalues

from gimwatch.denoc import DenocModel, chain_body_tree, read_body_tree
from gimwatch.errors import BackendWarning
from gimwatch.metrics.linear_analysis import analyze_linear, chain_configurations
from gimwatch.metrics.tracker import extreme_eigenvalues
from gimwatch.model.chains import chain_spec, generate_chain_urdf
from gimwatch.model.robots import Robot, load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene
from gimwatch.stress.reference_planar import PlanarChainReference

SPECS = {
    "paper": chain_spec(12),
    "spatial-mixed": chain_spec(
        12, axes="spatial", radius_m=0.04, joint_types=["revolute", "prismatic", "revolute"] * 4
    ),
    "tapered": chain_spec(
        12, mass_kg=2.2 * 0.3 ** np.arange(12), length_m=0.7 ** np.arange(12), axes="spatial"
    ),
}


@pytest.mark.parametrize("name", SPECS)
def test_chain_body_tree_equals_the_urdf_read_by_yourdfpy(name):
    spec = SPECS[name]
    direct, read = chain_body_tree(spec), read_body_tree(generate_chain_urdf(spec))
    assert direct.joint_names == read.joint_names
    for field in (
        "parent",
        "kind",
        "placement_rotation",
        "placement_translation",
        "axis",
        "mass",
        "com",
        "inertia",
    ):
        np.testing.assert_allclose(getattr(direct, field), getattr(read, field), atol=1e-15)


@pytest.mark.parametrize("name", SPECS)
def test_compiled_recursions_match_pinocchio(name):
    spec = SPECS[name]
    model = pin.buildModelFromXML(generate_chain_urdf(spec))
    model.gravity = pin.Motion(np.array([0.3, -9.81, 1.2]), np.zeros(3))
    data = model.createData()
    denoc = DenocModel.from_chain(spec)
    rng = np.random.default_rng(7)
    for q in chain_configurations(spec, 3, seed=1):
        v, a, tau = rng.standard_normal((3, spec.n))
        g = (0.3, -9.81, 1.2)
        M = pin.crba(model, data, q).copy()
        state = denoc.state(q)
        np.testing.assert_allclose(state.dense(), M, rtol=0, atol=1e-13 * np.abs(M).max())
        np.testing.assert_allclose(denoc.gim_diagonal(q), np.diag(M), rtol=1e-12)
        tau_ref = pin.rnea(model, data, q, v, a)
        np.testing.assert_allclose(
            denoc.inverse_dynamics(q, v, a, gravity=g),
            tau_ref,
            rtol=0,
            atol=1e-11 * np.abs(tau_ref).max(),
        )
        qdd_ref = pin.aba(model, data, q, v, tau)
        qdd = denoc.forward_dynamics(q, v, tau, gravity=g)
        assert np.linalg.norm(qdd - qdd_ref) <= 1e-9 * np.linalg.norm(qdd_ref)
        pin.crba(model, data, q)
        pin.cholesky.decompose(model, data)
        np.testing.assert_allclose(denoc.forward_dynamics_pivots(q), data.D, rtol=1e-9)
        kinetic, potential = denoc.energy(q, v, gravity=g)
        assert kinetic == pytest.approx(pin.computeKineticEnergy(model, data, q, v), rel=1e-12)
        assert potential == pytest.approx(
            pin.computePotentialEnergy(model, data, q), rel=1e-12, abs=1e-12
        )


def test_chain_limits_are_those_pinocchio_reads_and_configurations_stay_inside():
    """One source of a chain's limits: what its URDF says, drawn without a Pinocchio model."""
    spec = chain_spec(25, joint_types=["revolute", "prismatic"] * 12 + ["revolute"])
    model = pin.buildModelFromXML(generate_chain_urdf(spec))
    lower, upper = spec.position_limits()
    np.testing.assert_array_equal(lower, model.lowerPositionLimit)
    np.testing.assert_array_equal(upper, model.upperPositionLimit)
    np.testing.assert_array_equal(upper[::2], np.pi)  # revolute: a full turn
    np.testing.assert_array_equal(upper[1::2], np.asarray(spec.lengths_m[1::2]) / 2)  # rod/2
    robot = Robot(name="c", spec="c", model=model, urdf_xml="", source="<test>")
    many = chain_configurations(spec, 400, seed=9)
    assert np.all((lower <= many) & (many < upper))
    # the two ways in (analyze's O(n) path, and every other command) draw the same q
    np.testing.assert_array_equal(many[:4], random_configurations(robot, 4, seed=9))


@pytest.mark.parametrize("n", [5, 40, 200])
def test_matrix_free_kappa_matches_the_dense_eigensolver(n):
    q = chain_configurations(chain_spec(n), 1, seed=n)[0]
    state = DenocModel.from_chain(chain_spec(n)).state(q)
    # eigvalsh of the closed-form rod chain's M, not of DeNOC's own dense M
    values = np.linalg.eigvalsh(rod_chain_gim(q))
    found = extreme_eigenvalues(state, seed=0)
    assert found.kappa == pytest.approx(values[-1] / values[0], rel=1e-7)
    assert found.lambda_min == pytest.approx(values[0], rel=1e-7)


def test_matrix_free_kappa_matches_mpmath_at_50_digits():
    spec = chain_spec(8)
    q = np.linspace(-0.9, 0.7, 8)
    with mpmath.workdps(50):
        M = PlanarChainReference(spec).gim(q)
        values = sorted(mpmath.eigsy(M, eigvals_only=True))
        exact = float(values[-1] / values[0])
    found = extreme_eigenvalues(DenocModel.from_chain(spec).state(q), seed=3, rtol=1e-12)
    # κ ≈ 1.4e4, κ·eps ≈ 3e-12: the tolerance 2e-12 is the asked rtol on each end (κ to about
    # 2·rtol), below κ·eps; measured 0 to 4e-16 over seeds 0-4
    assert found.kappa == pytest.approx(exact, rel=2e-12)


@pytest.mark.parametrize(("n", "rel"), [(1_000, 1e-8), (5_000, 1e-5)])
def test_long_straight_chains_follow_the_closed_forms(n, rel):
    # measured κ errors: 5e-14 (1,000), 1.1e-6 (5,000: Lanczos reaches max_steps)
    record = analyze_linear(DenocModel.from_chain(chain_spec(n)), np.zeros(n), name="c")
    assert record.diagonal_ratio == pytest.approx(n**3, rel=1e-10)
    # κ from the banded closed-form pencil (tests/closed_forms.py), not from DeNOC
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    assert record.kappa == pytest.approx(lambda_max / lambda_min, rel=rel)
    assert record.pivot_ratio_backward == pytest.approx(1.8660254037844386, rel=1e-9)


#: κ/4n⁴ of the straight chain as published (README, benchmarks/longchain_kappa.csv).
PUBLISHED_KAPPA_OVER_4N4 = {1_000: 0.973, 10_000: 0.971}


def test_closed_form_pencil_equals_the_dense_eigensolver_at_a_thousand_links():
    n = 1_000
    values = np.linalg.eigvalsh(rod_chain_gim(np.zeros(n)))
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    assert lambda_max == pytest.approx(values[-1], rel=1e-13)
    # dense λmin carries an absolute error ~eps·λmax (relative ~1e-3 here): measured 1.6e-7
    assert lambda_min == pytest.approx(values[0], rel=1e-6)


@pytest.mark.parametrize(("n", "rel"), [(1_000, 1e-9), (10_000, 1e-6)])
def test_lanczos_kappa_of_the_clustered_straight_chain_is_tight(n, rel):
    # The hard case: the smallest eigenvalues cluster within relative gaps ~1/n² (3e-5 at
    # n = 1,000). Measured errors of the default rtol = 1e-10: 5e-14 (1,000), 2e-7 (10,000,
    # max_steps reached); a Lanczos stopped at rtol = 1e-3 is off by 4e-4 and 8e-4.
    lambda_min, lambda_max = straight_chain_extreme_eigenvalues(n)
    exact = lambda_max / lambda_min
    found = extreme_eigenvalues(DenocModel.from_chain(chain_spec(n)).state(np.zeros(n)))
    assert found.kappa == pytest.approx(exact, rel=rel), (found.kappa, exact)
    assert found.lambda_min == pytest.approx(lambda_min, rel=rel)
    assert found.lambda_max == pytest.approx(lambda_max, rel=1e-12)
    assert round(exact / (4 * n**4), 3) == PUBLISHED_KAPPA_OVER_4N4[n]


def test_hundred_thousand_links_diagonal_ratio_without_kappa():
    n = 100_000
    record = analyze_linear(
        DenocModel.from_chain(chain_spec(n)), np.zeros(n), name="c", metrics=("diagonal_ratio",)
    )
    assert record.kappa is None and record.diagonal_ratio == pytest.approx(n**3, rel=1e-9)


def _swing(robot, backend, duration=0.2, metrics=("diagonal_ratio",)):
    table = {
        "robot": robot,
        "duration": duration,
        "sample": duration / 4,
        "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
        "integrator": {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10},
        "dynamics": {"backend": backend},
        "watch": {"metrics": list(metrics)},
    }
    return run_scene(parse_scene(table, source="t.toml"))


def test_denoc_and_aba_simulations_agree_on_a_hundred_links():
    aba, denoc = _swing("chain:100", "aba"), _swing("chain:100", "denoc")
    np.testing.assert_allclose(denoc.q, aba.q, rtol=0, atol=1e-7)
    np.testing.assert_allclose(denoc.energy, aba.energy, rtol=0, atol=1e-8)
    np.testing.assert_allclose(
        denoc.watch["watch_diagonal_ratio"], aba.watch["watch_diagonal_ratio"], rtol=1e-12
    )


def test_long_chain_simulation_switches_to_denoc_and_builds_no_data(monkeypatch):
    def refuse(self):
        raise AssertionError("a Pinocchio Data was built")

    monkeypatch.setattr(Robot, "new_data", refuse)
    with pytest.warns(BackendWarning, match="using the O\\(n\\) denoc backend instead of aba"):
        run = _swing("chain:450", "aba", duration=0.02)
    assert run.t.size == 5 and np.all(np.isfinite(run.q)) and run.backend == "denoc"
    assert run.watch["watch_diagonal_ratio"][0] == pytest.approx(450**3, rel=1e-12)
    assert abs(run.energy[-1] - run.energy[0]) <= 1e-8 * abs(run.energy).max() + 1e-8


def test_floating_base_long_chain_keeps_the_numpy_recursions():
    robot = load_robot("chain:6", floating=True)
    denoc = DenocModel.from_urdf(robot.urdf_xml, floating=True, joint_order=robot.joint_names)
    assert denoc.linear is None
    q = random_configurations(robot, 1, seed=2)[0]
    np.testing.assert_allclose(
        denoc.gim_diagonal(q), np.diag(pin.crba(robot.model, robot.new_data(), q)), rtol=1e-12
    )


def test_simulate_backend_option_overrides_the_scene(tmp_path, capsys):
    import json

    from gimwatch.cli import main

    scene = tmp_path / "chain.toml"
    scene.write_text(
        'robot = "chain:30"\nduration = 0.05\nsample = 0.01\n'
        "[effects.gravity]\nvector = [0.0, -9.81, 0.0]\n"
        '[integrator]\nmethod = "RK4"\ndt = 0.001\n[dynamics]\nbackend = "aba"\n'
        '[watch]\nmetrics = ["diagonal_ratio"]\n'
    )
    results = {}
    for backend in ("aba", "denoc"):
        out = tmp_path / backend
        assert main(["simulate", str(scene), "-o", str(out), "--backend", backend]) == 0
        summary = json.loads((out / "summary.json").read_text())
        results[backend] = np.load(out / "trajectory.npz", allow_pickle=False)["q"]
        assert summary["backend"] == backend
    capsys.readouterr()
    np.testing.assert_allclose(results["denoc"], results["aba"], rtol=0, atol=1e-10)


def test_compiled_state_operators_match_the_closed_form():
    # the compiled kernels behind analyze_linear and extreme_eigenvalues, checked directly
    # (δ alone cannot see a uniform error of the diagonal; κ alone hides a small one of M⁻¹)
    n = 9
    spec = chain_spec(n)
    q = chain_configurations(spec, 1, seed=4)[0]
    model = DenocModel.from_chain(spec)
    state = model.state(q)
    M = rod_chain_gim(q)
    np.testing.assert_allclose(model.to_public(state.diagonal()), np.diag(M), rtol=1e-13)
    y = np.random.default_rng(1).standard_normal(n)
    x = model.to_public(state.solve(model.to_internal("y", y)))
    backward = np.linalg.norm(M @ x - y) / (np.linalg.norm(M, 2) * np.linalg.norm(x))
    assert backward <= 1e-14, backward
