"""κ_S = κ₂(D^-1/2 M D^-1/2), ``kappa_equilibrated``: against NumPy on Pinocchio's M, closed
forms, the O(n) path, the κ tracker, the same robot written in millimetres, and mpmath."""

from __future__ import annotations

import json
from pathlib import Path

import mpmath
import numpy as np
import pinocchio as pin
import pytest
import scipy.linalg
from closed_forms import rod_chain_gim

from gimwatch.cli import main
from gimwatch.errors import ConditioningError
from gimwatch.metrics.analyze import analyze
from gimwatch.metrics.equilibrated import ScaledProducts, equilibrated_dense
from gimwatch.metrics.registry import GimState, evaluate
from gimwatch.metrics.tracker import KappaTracker, PinocchioProducts
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch.sources import GivenMatrix

UNITS = Path(__file__).parent / "data" / "units"
EPS = np.finfo(float).eps


def _kappa_s(M: np.ndarray) -> float:
    """NumPy's κ₂ of D^-1/2 M D^-1/2, written here without gimwatch."""
    d = np.sqrt(np.diag(M))
    values = np.linalg.eigvalsh(M / np.outer(d, d))
    return values[-1] / values[0]


def _kappa_s_of(M: np.ndarray) -> float:
    return evaluate(("kappa_equilibrated",), GimState(GivenMatrix(len(M)), full=True, matrix=M))[
        "kappa_equilibrated"
    ]


@pytest.mark.parametrize(
    ("spec", "floating"),
    [("ur5", False), ("panda", False), ("solo12", True), (str(UNITS / "slider_arm_m.urdf"), True)],
)
def test_analyze_json_matches_numpy_on_pinocchios_crba(spec, floating, capsys):
    args = ["analyze", spec, "--random", "3", "--seed", "5", "--json"]
    assert main(args + (["--floating"] if floating else [])) == 0
    records = json.loads(capsys.readouterr().out)["configurations"]
    robot = load_robot(spec, floating=floating)
    data = robot.model.createData()
    for record in records:
        M = pin.crba(robot.model, data, np.array(record["q"]))
        M = np.triu(M) + np.triu(M, 1).T
        assert record["kappa_equilibrated"] == pytest.approx(_kappa_s(M), rel=1e-9)
        # κ ≤ δ·κ_S always: δ is the spread of the diagonal, κ_S the coupling
        assert record["kappa"] <= record["diagonal_ratio"] * record["kappa_equilibrated"] * (
            1 + 1e-9
        )


def test_a_diagonal_gim_has_kappa_s_one_and_diagonal_scaling_leaves_it():
    assert _kappa_s_of(np.diag([1e-6, 3.0, 7e5])) == pytest.approx(1.0, abs=1e-14)
    robot = load_robot("panda")
    M = pin.crba(robot.model, robot.model.createData(), random_configurations(robot, 1, seed=2)[0])
    M = np.triu(M) + np.triu(M, 1).T
    T = np.diag(10.0 ** np.linspace(-4, 4, robot.nv))  # any change of unit per coordinate
    assert _kappa_s_of(T @ M @ T) == pytest.approx(_kappa_s_of(M), rel=1e-9)
    assert np.linalg.cond(T @ M @ T) > 1e6 * np.linalg.cond(M)


def test_two_rod_chain_closed_form():
    """Two uniform rods (m, l): M = m l² [[5/3 + c, 1/3 + c/2], [1/3 + c/2, 1/3]], c = cos q₂;
    S has off-diagonal s = M₁₂/√(M₁₁M₂₂), eigenvalues 1 ± |s|, κ_S = (1 + |s|)/(1 − |s|)."""
    for q2 in (0.0, 0.7, 2.0, 3.0):
        c = np.cos(q2)
        s = (1 / 3 + c / 2) / np.sqrt((5 / 3 + c) / 3)
        expected = (1 + abs(s)) / (1 - abs(s))
        record = analyze("chain:2", [0.4, q2]).results[0]
        assert record.kappa_equilibrated == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("n", [12, 40])
def test_o_n_path_matches_the_rod_chain_closed_form(n):
    dense = analyze(f"chain:{n}", random=2, seed=1, backend="crba").results
    linear = analyze(f"chain:{n}", random=2, seed=1, backend="denoc").results
    for a, b in zip(dense, linear, strict=True):
        expected = _kappa_s(rod_chain_gim(np.array(a.q)))
        assert a.kappa_equilibrated == pytest.approx(expected, rel=1e-9)
        assert b.method == "denoc-linear"
        assert b.kappa_equilibrated == pytest.approx(expected, rel=1e-8)


def test_the_tracker_tracks_kappa_s_on_scaled_products():
    robot = load_robot("panda")
    data = robot.model.createData()
    qs = random_configurations(robot, 4, seed=7)
    products = ScaledProducts(
        PinocchioProducts(robot), lambda q: gim_diagonal(robot, q, data=robot.new_data())
    )
    dense = equilibrated_dense(lambda q: pin.crba(robot.model, data, q))
    tracker = KappaTracker(products, robot.nv, dense=dense)
    for q in qs:
        M = pin.crba(robot.model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        assert tracker.sample(q).kappa == pytest.approx(_kappa_s(M), rel=1e-8)


def _file_records(unit: str, q: list[float], floating: bool, capsys) -> dict:
    args = ["analyze", str(UNITS / f"slider_arm_{unit}.urdf"), "--json", "--q", *map(str, q)]
    assert main(args + (["--floating"] if floating else [])) == 0
    captured = capsys.readouterr()
    return json.loads(captured.out)["configurations"][0] | {"stderr": captured.err}


@pytest.mark.parametrize("floating", [False, True])
def test_kappa_s_is_the_same_when_the_file_is_written_in_millimetres(floating, capsys):
    joints = [0.3, -0.8, 1.1, 0.025]  # the last is the finger's slide, m
    base = [
        0.1,
        -0.2,
        0.3,
        *(np.array([0.1, 0.2, -0.3, 0.9]) / np.linalg.norm([0.1, 0.2, -0.3, 0.9])),
    ]
    q_m = (base if floating else []) + joints
    q_mm = ([1000 * x for x in base[:3]] + base[3:] if floating else []) + joints[:3] + [25.0]
    metres = _file_records("m", q_m, floating, capsys)
    millimetres = _file_records("mm", q_mm, floating, capsys)
    assert millimetres["kappa_equilibrated"] == pytest.approx(
        metres["kappa_equilibrated"], rel=1e-9
    )
    assert millimetres["kappa"] > 100 * metres["kappa"]  # κ and δ follow the unit of length
    assert millimetres["diagonal_ratio"] > 100 * metres["diagonal_ratio"]
    assert "mixes units" in metres["stderr"] and "kappa_equilibrated does not" in metres["stderr"]


def test_no_units_note_on_a_revolute_arm(capsys):
    assert main(["analyze", "ur5", "--json"]) == 0
    assert "mixes units" not in capsys.readouterr().err


def test_a_nonpositive_diagonal_is_refused():
    with pytest.raises(ConditioningError):
        _kappa_s_of(np.array([[1.0, 0.0], [0.0, -1.0]]))


def test_cholesky_loses_digits_by_kappa_s_not_kappa():
    """van der Sluis: a Cholesky solve of M = D S D is as accurate as one of S. Against a
    50-digit mpmath solve of the same float M: δ = 1e12, κ_S ≈ 4, κ ≈ 1e12."""
    rng = np.random.default_rng(0)
    n = 8
    A = rng.standard_normal((n, n))
    S = np.eye(n) + 0.05 * (A + A.T)
    D = np.diag(10.0 ** np.linspace(0, 6, n))
    M = D @ S @ D
    tau = M @ rng.standard_normal(n)
    x = scipy.linalg.cho_solve(scipy.linalg.cho_factor(M), tau)
    with mpmath.workdps(50):
        exact = mpmath.lu_solve(mpmath.matrix(M.tolist()), mpmath.matrix(tau.tolist()))
        exact = np.array([float(v) for v in exact])
    w = np.sqrt(np.diag(M))  # the D^1/2-weighted (energy-like) norm
    error = np.linalg.norm(w * (x - exact)) / np.linalg.norm(w * exact)
    kappa, kappa_s = np.linalg.cond(M), _kappa_s_of(M)
    assert kappa > 1e11 and kappa_s < 10
    assert error < 10 * kappa_s * EPS < 1e-6 * kappa * EPS


def test_explain_modes_of_s():
    from gimwatch.explain.modes import gim_modes

    robot = load_robot("panda")
    q = random_configurations(robot, 1, seed=4)[0]
    M = pin.crba(robot.model, robot.model.createData(), q)
    M = np.triu(M) + np.triu(M, 1).T
    modes = gim_modes(robot, q, metric="kappa_equilibrated")
    assert modes.kappa == pytest.approx(_kappa_s(M), rel=1e-10)
    u = np.array(modes.lowest.vector)
    v = u / np.sqrt(np.diag(M))
    assert v @ M @ v == pytest.approx(modes.lowest.eigenvalue, rel=1e-10)  # S u = μ u
    assert sum(p for _, p in modes.lowest.joints) == pytest.approx(1.0)


def test_survey_samples_kappa_s():
    from gimwatch.survey.run import sample_metrics

    robot = load_robot("ur5")
    qs = random_configurations(robot, 3, seed=9)
    values = sample_metrics(robot, qs)["kappa_equilibrated"]
    data = robot.model.createData()
    for q, value in zip(qs, values, strict=True):
        M = pin.crba(robot.model, data, q)
        assert value == pytest.approx(_kappa_s(np.triu(M) + np.triu(M, 1).T), rel=1e-9)


def test_the_watch_and_a_map_report_kappa_s():
    from gimwatch.explain.maps import metrics_at
    from gimwatch.watch.watch import Watch

    robot = load_robot("ur5")
    qs = random_configurations(robot, 2, seed=11)
    watch = Watch(robot, ("kappa", "kappa_equilibrated"))
    data = robot.model.createData()
    expected = []
    for t, q in enumerate(qs):
        watch.sample(float(t), q)
        M = pin.crba(robot.model, data, q)
        expected.append(_kappa_s(np.triu(M) + np.triu(M, 1).T))
    np.testing.assert_allclose(watch.array("kappa_equilibrated"), expected, rtol=1e-9)
    dense = metrics_at("ur5", "crba", qs, ("kappa_equilibrated",))
    np.testing.assert_allclose(dense[0], expected, rtol=1e-9)
    chain = np.array([[0.3, -0.2, 0.5], [1.0, 0.1, -0.4]])
    linear = metrics_at("chain:3", "denoc", chain, ("kappa_equilibrated", "kappa"))
    references = [_kappa_s(rod_chain_gim(q)) for q in chain]
    np.testing.assert_allclose(linear[0], references, rtol=1e-8)


def test_the_analyze_guide_quotes_the_units_note(capsys):
    assert main(["analyze", "solo12"]) == 0
    note = capsys.readouterr().err.strip().splitlines()[0]
    page = Path(__file__).resolve().parents[1] / "docs" / "guide" / "analyze.md"
    assert note in page.read_text(encoding="utf-8").splitlines()


@pytest.mark.parametrize("spec", ["chain:30", "panda"])
def test_the_watch_tracks_kappa_s_at_o_n(spec):
    from gimwatch.watch.watch import Watch

    robot = load_robot(spec)
    qs = random_configurations(robot, 4, seed=13)
    watch = Watch(robot, ("kappa_equilibrated_tracked",))
    data = robot.model.createData()
    expected = []
    for t, q in enumerate(qs):
        watch.sample(float(t), q)
        M = pin.crba(robot.model, data, q)
        expected.append(_kappa_s(np.triu(M) + np.triu(M, 1).T))
    assert not watch.full  # M is never formed
    np.testing.assert_allclose(watch.array("kappa_equilibrated_tracked"), expected, rtol=1e-8)


def test_the_o_n_path_notes_mixed_units_of_a_file(capsys):
    arm = str(UNITS / "slider_arm_m.urdf")
    assert main(["analyze", arm, "--backend", "denoc", "--q", "0.3", "-0.8", "1.1", "0.025"]) == 0
    assert "mixes units (1 length and 3 angle coordinates)" in capsys.readouterr().err
    assert not analyze("chain:5", backend="denoc").mixed_units
    assert analyze("chain:4", backend="crba").units == (0, 4)


def test_the_scaled_tracker_is_certified_by_its_own_sylvester_counts():
    # no dense fallback: every sample is certified through the pivots of M − σ·D (Pinocchio's
    # sparse LDLᵀ), and its bracket holds NumPy's κ(S) on a smooth path
    robot = load_robot("panda")
    data = robot.model.createData()
    products = ScaledProducts(
        PinocchioProducts(robot), lambda q: gim_diagonal(robot, q, data=robot.new_data())
    )
    assert products.shifts_by_diagonal
    tracker = KappaTracker(products, robot.nv)
    start, end = random_configurations(robot, 2, seed=11)
    for s in np.linspace(0.0, 1.0, 25):
        q = (1 - s) * start + s * end
        M = pin.crba(robot.model, data, q)
        exact = _kappa_s(np.triu(M) + np.triu(M, 1).T)
        sample = tracker.sample(q)
        assert sample.certified and np.isfinite(sample.error_estimate)
        assert sample.kappa * (1 - 1e-12) <= exact <= sample.kappa * (1 + sample.error_estimate)
