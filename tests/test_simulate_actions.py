"""on_alarm = tighten / switch-backend, and divergence (non-finite values, step-size collapse)."""

import numpy as np
import pytest

from gimwatch.errors import SceneError
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import MOST_ACCURATE_BACKEND, RTOL_FLOOR, Simulation, run_scene

GRAVITY = {"gravity": {"vector": [0.0, -9.81, 0.0]}}


def scene(robot="chain:4", *, integrator=None, duration=1.0, sample=0.05, **extra):
    table = {"robot": robot, "duration": duration, "sample": sample, **extra}
    table["integrator"] = integrator or {"method": "DOP853", "rtol": 1e-8, "atol": 1e-8}
    return parse_scene(table, source="test.toml")


def watch(action, threshold=50.0, metric="diagonal_ratio"):
    return {"metrics": [metric], "alarm_threshold": threshold, "on_alarm": action}


def test_tighten_lowers_rtol_in_proportion_to_the_estimate():
    run = run_scene(scene(effects=GRAVITY, watch=watch("tighten")))
    assert run.status == "completed" and run.actions
    delta = run.watch["watch_diagonal_ratio"]
    # the straight 4-link chain starts at delta = n^3 = 64 > 50, so the first sample after
    # t0 is above the threshold: rtol = 1e-8 * 50 / delta there
    first = run.actions[0]
    assert first.startswith(f"t = {run.watch['watch_t'][1]:.6g} s")
    expected = max(1e-8 * 50.0 / delta[1], RTOL_FLOOR)
    assert first.endswith(f"-> {expected:.3g}")


def test_tighten_is_more_accurate_than_the_fixed_tolerance_it_starts_from():
    reference = run_scene(
        scene(effects=GRAVITY, integrator={"method": "DOP853", "rtol": 1e-13, "atol": 1e-13})
    )
    loose = {"method": "RK45", "rtol": 1e-5, "atol": 1e-5}
    fixed = run_scene(scene(effects=GRAVITY, integrator=loose))
    tight = run_scene(scene(effects=GRAVITY, integrator=loose, watch=watch("tighten", 20.0)))
    error_fixed = np.max(np.abs(fixed.q - reference.q))
    error_tight = np.max(np.abs(tight.q - reference.q))
    assert error_tight < 0.5 * error_fixed, (error_tight, error_fixed)
    assert tight.rhs_evaluations > fixed.rhs_evaluations


def test_switch_backend_moves_to_the_most_accurate_one_and_keeps_the_trajectory():
    base = {"effects": GRAVITY, "dynamics": {"backend": "crba-cholesky"}}
    run = run_scene(scene(**base, watch=watch("switch-backend", 60.0)))  # delta(0) = 64
    assert run.status == "completed"
    assert len(run.actions) == 1 and run.actions[0].endswith(
        f"backend crba-cholesky -> {MOST_ACCURATE_BACKEND}"
    )
    plain = run_scene(scene(effects=GRAVITY))
    np.testing.assert_allclose(run.q, plain.q, atol=1e-6)


@pytest.mark.parametrize(
    ("extra", "message"),
    [
        (
            {"integrator": {"method": "RK4", "dt": 0.01}, "watch": watch("tighten")},
            "test.toml: watch.on_alarm: tighten needs an adaptive integrator "
            "(RK45, DOP853, Radau), got RK4",
        ),
        (
            {"integrator": {"method": "LSODA"}, "watch": watch("tighten")},
            "test.toml: watch.on_alarm: tighten needs an adaptive integrator "
            "(RK45, DOP853, Radau), got LSODA",
        ),
        (
            {"watch": watch("switch-backend")},
            "test.toml: watch.on_alarm: switch-backend moves to aba, which the scene already "
            "uses (dynamics.backend)",
        ),
    ],
)
def test_actions_that_cannot_apply_are_scene_errors(extra, message):
    with pytest.raises(SceneError) as info:
        Simulation(scene(**extra))
    assert str(info.value) == message


def _runaway(q, v, tau):
    """v' = 10 (1 + v²), so v = tan(10 t) blows up at t = π/20."""
    return 10.0 * (1.0 + v * v)


def _poisoned(q, v, tau):
    """NaN accelerations once v > 0.2 (v = t until then)."""
    return np.full_like(v, np.nan) if v[0] > 0.2 else np.ones_like(v)


def test_step_size_collapse_stops_with_time_and_cause_and_keeps_results():
    simulation = Simulation(scene("chain:1", duration=1.0, sample=0.01))
    simulation.backend.forward_dynamics = _runaway  # the energy still comes from aba
    run = simulation.run()
    assert run.status == "diverged"
    assert "step size collapsed" in run.message
    t_stop = float(run.message.split("t = ")[1].split(" s")[0])
    assert t_stop == pytest.approx(np.pi / 20, rel=1e-3)
    assert run.t.size == 16 and np.all(np.isfinite(run.v))  # samples 0 .. 0.15 s kept
    np.testing.assert_allclose(run.v[:, 0], np.tan(10 * run.t), rtol=1e-5)


def test_non_finite_acceleration_stops_with_time_and_cause():
    simulation = Simulation(scene("chain:1", duration=1.0, sample=0.01))
    simulation.backend.forward_dynamics = _poisoned
    run = simulation.run()
    assert run.status == "diverged"
    assert run.message.startswith("non-finite acceleration from the aba backend at t = ")
    t_stop = float(run.message.split("t = ")[1].split(" s")[0])
    assert 0.2 < t_stop < 0.5 and 0.0 < run.t[-1] <= t_stop and np.all(np.isfinite(run.q))
