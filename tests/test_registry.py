"""The metric registry: one definition per metric, the same value through every provider.

References are computed here with plain NumPy from Pinocchio's M (eigvalsh, the diagonal, a
Cholesky factor of M and of M with its coordinates reversed), independently of gimwatch's
conditioning module; the O(n) path (DeNOC, no M formed) must agree with them.
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.denoc import DenocModel
from gimwatch.metrics.mass_matrix_sources import DenocLinear, PinocchioSource
from gimwatch.metrics.registry import METRICS, GimState, evaluate
from gimwatch.model.robots import load_robot
from gimwatch.model.sampling import random_configurations
from gimwatch.watch.sources import GivenMatrix

ROOT = Path(__file__).resolve().parents[1]


def _references(M: np.ndarray) -> dict[str, float]:
    values = np.linalg.eigvalsh(M)
    forward = np.diag(np.linalg.cholesky(M)) ** 2
    backward = np.diag(np.linalg.cholesky(M[::-1, ::-1])) ** 2
    return {
        "kappa": values[-1] / values[0],
        "diagonal_ratio": np.diag(M).max() / np.diag(M).min(),
        "pivot_ratio_forward": forward.max() / forward.min(),
        "pivot_ratio_backward": backward.max() / backward.min(),
    }


@pytest.mark.parametrize("name", ["ur5", "panda", "chain:12"])
def test_every_provider_gives_the_reference_values(name):
    robot = load_robot(name)
    q = random_configurations(robot, 1, seed=3)[0]
    M = pin.crba(robot.model, robot.model.createData(), q)
    reference = _references(M)
    crba = GimState(PinocchioSource(robot, robot.new_data()), q, full=True)
    given = GimState(GivenMatrix(robot.nv), full=True, matrix=M)
    for state in (crba, given):
        got = evaluate(tuple(reference), state)
        for key, value in reference.items():
            assert got[key] == pytest.approx(value, rel=1e-10), key
    model = DenocModel.from_urdf(robot.urdf_xml, source=robot.source, joint_order=robot.joint_names)
    # no M: diag, pivots and κ by O(n) recursions and Lanczos
    linear = GimState(DenocLinear(model), q, lanczos=(0, 1e-12))
    got = evaluate(("kappa", "diagonal_ratio", "pivot_ratio_backward"), linear)
    assert got["kappa"] == pytest.approx(reference["kappa"], rel=1e-9)
    assert got["diagonal_ratio"] == pytest.approx(reference["diagonal_ratio"], rel=1e-12)
    assert got["pivot_ratio_backward"] == pytest.approx(reference["pivot_ratio_backward"], rel=1e-9)


def test_the_o_n_path_refuses_metrics_that_need_m():
    robot = load_robot("chain:5")
    model = DenocModel.from_urdf(robot.urdf_xml, source=robot.source, joint_order=robot.joint_names)
    state = GimState(DenocLinear(model), np.zeros(5))
    with pytest.raises(Exception, match="never forms"):
        evaluate(("pivot_ratio_forward",), state)


def test_each_state_quantity_is_computed_once(monkeypatch):
    from gimwatch.metrics import conditioning

    calls = {"eig": 0}
    original = conditioning.eigenvalues

    def counting(M):
        calls["eig"] += 1
        return original(M)

    monkeypatch.setattr(conditioning, "eigenvalues", counting)
    M = np.diag([4.0, 2.0, 1.0]) + 0.1
    evaluate(
        ("kappa", "eigenvalues", "scaled_diagonal_ratio"),
        GimState(GivenMatrix(3), full=True, matrix=M),
    )
    assert calls["eig"] == 1


def test_one_definition_of_the_ratios():
    """κ, δ and the pivot ratios are one max/min (conditioning.extreme_ratio): no other module
    divides a maximum by a minimum of eigenvalues, diagonals or pivots."""
    pattern = re.compile(r"\.max\(\) / [\w.]*\.min\(\)|\[-1\] / [\w.]*\[0\]")
    found = [
        f"{path.relative_to(ROOT)}:{k}"
        for path in sorted((ROOT / "gimwatch").rglob("*.py"))
        for k, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1)
        if pattern.search(line)
    ]
    allowed = {
        "gimwatch/metrics/conditioning.py",
        "gimwatch/survey/trajectory.py",  # κ spread
        "gimwatch/bench/watch_overhead.py",  # the user's own two lines, the bench's baseline
    }
    assert [f for f in found if f.split(":")[0] not in allowed] == [], found
    assert sum(f.startswith("gimwatch/metrics/conditioning.py") for f in found) == 1


def test_every_metric_documents_its_contract():
    for name, cls in METRICS.items():
        assert cls.name == name and cls.__doc__, name
        assert isinstance(cls.full, bool) and isinstance(cls.vector, bool)


def test_kappa_tracked_records_fallbacks_and_falls_back_to_dense():
    """Each sample's fallback and error bound are kept; a failing O(n) solve goes dense."""
    robot = load_robot("chain:12")
    data = robot.new_data()
    metric = METRICS["kappa_tracked"]()
    qs = random_configurations(robot, 4, seed=3)
    for i, q in enumerate(qs):
        state = GimState(PinocchioSource(robot, data), q)
        if i == 2:  # the O(n) solve fails (e.g. M not positive definite to its products)
            metric.tracker.sample = _failing(metric.tracker)
        kappa = metric(state)
        values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), q))
        # the tracker's documented rtol 1e-10 per end (κ to ~2e-10), with a margin of 2.5
        assert kappa == pytest.approx(values[-1] / values[0], rel=5e-10)
    assert len(metric.fallbacks) == len(metric.error_estimates) == 4
    assert metric.fallbacks[0] == "start" and metric.fallbacks[2] == "dense"
    # each end certified to rtol (κ's bracket 2·rtol/(1 − rtol)); a dense sample's round-off
    # n·eps·κ (the patched sample stays in place: samples 2 and 3 are dense)
    assert metric.error_estimates[:2] == pytest.approx([2e-10 / (1 - 1e-10)] * 2, rel=1e-6)
    for i in (2, 3):
        values = np.linalg.eigvalsh(pin.crba(robot.model, robot.new_data(), qs[i]))
        eps_kappa = robot.nv * np.finfo(float).eps * values[-1] / values[0]
        assert metric.error_estimates[i] == pytest.approx(eps_kappa, rel=1e-6)


def _failing(tracker):
    """The tracker's sample with its O(n) path raising, as a non-converging sample does."""
    from gimwatch.errors import ConditioningError

    def products_fail(q):
        raise ConditioningError("no convergence")

    def sample(q):
        saved = tracker._denoc, tracker.products.configure
        tracker._denoc, tracker.products.configure = None, products_fail
        try:
            return type(tracker).sample(tracker, q)
        finally:
            tracker._denoc, tracker.products.configure = saved

    return sample
