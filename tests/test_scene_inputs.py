"""New scene entry points: Python torque laws, q in user coordinates, registries as names.

References: the closed-form rod under a constant torque (θ(t) = τ t² / (2 I)), Pinocchio's
own (cos θ, sin θ) convention (``pin.integrate`` from the neutral configuration), and the
registries themselves for the names the schema and the CLI accept.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.cli import main
from gimwatch.errors import GimwatchError, SceneError
from gimwatch.model.configuration import UNIT_TOLERANCE, ConfigurationError, user_configuration
from gimwatch.model.robots import load_robot
from gimwatch.simulation import alarm_actions, backends, effects, integrators, torque_laws
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import Simulation, run_scene
from gimwatch.simulation.torque_laws import TorqueLawError

ROD_MASS, ROD_LENGTH = 2.2, 1.0
ROD_INERTIA = ROD_MASS * ROD_LENGTH**2 / 3  # slender rod about its end


def _scene(robot="chain:1", **extra):
    table = {"robot": robot, "duration": 0.2, "sample": 0.05, **extra}
    return parse_scene(table, source="law.toml")


# -- callable torque laws -------------------------------------------------------------
def test_a_python_torque_law_drives_the_rod_like_the_closed_form():
    tau = 0.7
    run = run_scene(
        _scene(integrator={"method": "DOP853", "rtol": 1e-12, "atol": 1e-12}),
        torque_law=lambda t, q, v: np.array([tau]),
    )
    assert run.status == "completed" and run.effects == ("torque_law",)
    np.testing.assert_allclose(run.q[:, 0], tau * run.t**2 / (2 * ROD_INERTIA), atol=1e-10)
    assert run.energy is None  # a Python law is not conservative


def test_a_python_law_equals_the_toml_pd_law_on_continuous_joints():
    # the TOML pd law wraps angle errors with pin.difference; the callable does it by hand
    kp, kd, target = 4.0, 1.0, 0.4
    toml = run_scene(
        _scene(
            "kinova",
            q=0.0,
            effects={"torque": {"law": "pd", "kp": kp, "kd": kd, "target": target}},
        )
    )
    model = load_robot("kinova").model
    q_star = pin.integrate(model, pin.neutral(model), np.full(model.nv, target))

    def pd(t, q, v):
        return kp * pin.difference(model, q, q_star) - kd * v

    mine = run_scene(_scene("kinova", q=0.0), torque_law=pd)
    np.testing.assert_allclose(mine.q, toml.q, rtol=0, atol=1e-12)


@pytest.mark.parametrize(
    ("law", "message"),
    [
        (
            lambda t, q, v: np.zeros(2),
            "torque law <lambda>: must return shape (1,) (nv of chain_1), got (2,) at t = 0 s",
        ),
        (
            lambda t, q, v: np.array([np.nan]),
            "torque law <lambda>: must return finite values, got [nan] at t = 0 s",
        ),
        (
            lambda t, q, v: np.array([1j]),
            "torque law <lambda>: must return real numbers, got dtype complex128 at t = 0 s",
        ),
        (
            lambda t, q, v: 1 / 0,
            "torque law <lambda>: raised ZeroDivisionError at t = 0 s: division by zero",
        ),
    ],
)
def test_a_bad_python_law_is_one_clear_error_naming_it(law, message):
    with pytest.raises(TorqueLawError) as info:
        run_scene(_scene(), torque_law=law)
    assert str(info.value) == message


def test_a_non_callable_law_is_refused_at_build_time():
    with pytest.raises(TorqueLawError, match="must be a callable tau"):
        Simulation(_scene(), torque_law=3.0)


# -- q in user coordinates ------------------------------------------------------------
def test_q_zero_is_every_angle_zero_and_the_neutral_base():
    robot = load_robot("kinova")
    np.testing.assert_array_equal(Simulation(_scene("kinova", q=0.0)).q0, pin.neutral(robot.model))
    solo = Simulation(_scene("solo12", base="floating", q=0.0))
    np.testing.assert_array_equal(solo.q0, pin.neutral(solo.robot.model))


def test_continuous_joints_by_angle_in_numbers_lists_and_tables():
    robot = load_robot("kinova")
    model = robot.model
    angles = np.array([0.3, 3.5, 1.2, -0.4, 2.0, -2.5])
    expected = pin.integrate(model, pin.neutral(model), angles)  # Pinocchio's (cos, sin)
    by_list = Simulation(_scene("kinova", q=angles.tolist())).q0
    np.testing.assert_allclose(by_list, expected, rtol=0, atol=1e-15)
    table = dict(zip(robot.joint_names, angles.tolist(), strict=True))
    np.testing.assert_allclose(Simulation(_scene("kinova", q=table)).q0, expected, atol=1e-15)
    raw = Simulation(_scene("kinova", q=expected.tolist())).q0  # Pinocchio's 9 numbers
    np.testing.assert_allclose(raw, expected, atol=1e-15)
    number = Simulation(_scene("kinova", q=0.3)).q0
    np.testing.assert_allclose(number, pin.integrate(model, pin.neutral(model), np.full(6, 0.3)))


def test_unit_blocks_within_the_tolerance_are_normalised_beyond_it_refused():
    robot = load_robot("kinova")
    q = pin.neutral(robot.model)
    q[0] = 1.0 + 0.5 * UNIT_TOLERANCE
    fixed = user_configuration(robot, q, key="q")
    assert np.linalg.norm(fixed[:2]) == pytest.approx(1.0, abs=1e-15)
    q[0] = 1.0 + 2 * UNIT_TOLERANCE
    with pytest.raises(ConfigurationError) as info:
        user_configuration(robot, q, key="q")
    assert str(info.value) == (
        "q: (cos, sin) of joint j2s6s200_joint_1 must have norm 1 (within 1e-06), got norm 1"
    )


@pytest.mark.parametrize(
    ("q", "message"),
    [
        (
            [0.0] * 7 + [0.1] * 12,
            "law.toml: q: quaternion (qx, qy, qz, qw) of joint root_joint must have norm 1 "
            "(within 1e-06), got norm 0",
        ),
        (
            {"root_joint": 0.1},
            "law.toml: q.root_joint: joint is a free-flyer joint with 7 coordinates; "
            "give q as a list",
        ),
        ({"knee": 0.1}, "law.toml: q.knee: unknown joint; solo12 has root_joint, FL_HAA"),
        (
            [0.0] * 5,
            "law.toml: q: must have 19 values (q-coordinates of solo12), got 5",
        ),
    ],
)
def test_bad_q_on_a_floating_base_names_the_file_key_and_joint(q, message):
    with pytest.raises(SceneError) as info:
        Simulation(_scene("solo12", base="floating", q=q))
    assert str(info.value).startswith(message), str(info.value)
    assert "quaternion" not in message or "root_joint" in message


def test_messages_about_continuous_joints_never_say_quaternion():
    with pytest.raises(GimwatchError) as info:
        Simulation(_scene("kinova", q=[1.0] * 4))
    assert "quaternion" not in str(info.value)
    assert "continuous joints by angle" in str(info.value)


def test_analyze_reads_continuous_joints_by_angle(capsys):
    assert main(["analyze", "kinova", "--json", "--q", "0", "0", "0", "0", "0", "0"]) == 0
    by_angle = capsys.readouterr().out
    assert main(["analyze", "kinova", "--json"]) == 0
    assert capsys.readouterr().out == by_angle  # angle 0 everywhere is the neutral q
    code = main(["analyze", "kinova", "--q", "1.2", "0", "0", "0", "1", "0", "1", "0", "0"])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1
    assert "--q: (cos, sin) of joint j2s6s200_joint_1 must have norm 1" in err


# -- registries ------------------------------------------------------------------------
def test_the_schema_and_the_cli_read_the_live_registries(capsys):
    from gimwatch.simulation import scene

    assert scene.SCIPY_METHODS + scene.FIXED_STEP_METHODS == tuple(integrators.INTEGRATORS)
    assert scene.BACKENDS == tuple(backends.BACKENDS)
    assert scene.ON_ALARM_ACTIONS == tuple(alarm_actions.ALARM_ACTIONS)
    assert tuple(scene.EFFECT_KEYS) == tuple(effects.EFFECTS)
    with pytest.raises(SystemExit):
        main(["simulate", "--help"])
    assert "{" + ",".join(backends.BACKENDS) + "}" in capsys.readouterr().out


def test_a_registered_integrator_is_accepted_by_the_scene(monkeypatch):
    # adding an integrator touches its module only: the schema sees it at once
    class Heun(integrators.FixedStepIntegrator):
        name = "heun"

        def step(self, f, chart, t, q, v, dt):
            a1 = f(t, q, v)
            q1, v1 = chart.integrate(q, dt * v), v + dt * a1
            a2 = f(t + dt, q1, v1)
            return chart.integrate(q, 0.5 * dt * (v + v1)), v + 0.5 * dt * (a1 + a2)

    monkeypatch.setitem(integrators.INTEGRATORS, "heun", Heun)
    run = run_scene(_scene(integrator={"method": "heun", "dt": 0.001}), torque_law=None)
    assert run.status == "completed" and run.steps == 200
    with pytest.raises(ValueError, match="already registered"):
        integrators.register(Heun)


def test_a_registered_torque_law_is_accepted_by_the_scene(monkeypatch):
    class Ramp(torque_laws.TorqueLaw):
        name = "ramp"
        parameters = (torque_laws.Parameter("slope", "joint", required=True),)

        def __init__(self, robot, params, *, source):
            super().__init__(robot, params, source=source)
            self.slope = self.vector("slope")

        def __call__(self, t, q, v):
            return self.slope * t

    monkeypatch.setitem(torque_laws.TORQUE_LAWS, "ramp", Ramp)
    run = run_scene(
        _scene(
            effects={"torque": {"law": "ramp", "slope": 0.6}},
            integrator={"method": "DOP853", "rtol": 1e-12, "atol": 1e-12},
        )
    )
    # θ'' = s t / I  ->  θ = s t³ / (6 I)
    np.testing.assert_allclose(run.q[:, 0], 0.6 * run.t**3 / (6 * ROD_INERTIA), atol=1e-10)


def test_progress_stops_a_run_by_returning_a_message():
    calls = []

    def budget(fraction):
        calls.append(fraction)
        return "enough" if len(calls) == 3 else None

    run = Simulation(_scene(integrator={"method": "RK4", "dt": 0.01})).run(progress=budget)
    assert (run.status, run.message, run.steps) == ("stopped", "enough", 3)


@pytest.mark.parametrize("method", sorted(integrators.INTEGRATORS))
@pytest.mark.parametrize("argument", ["q", "v"])
def test_a_law_that_writes_to_q_or_v_is_an_error_naming_it_on_every_integrator(method, argument):
    """Writing to the state would change the run behind the integrator's back (silently)."""
    robot = "kinova" if argument == "q" else "chain:3"  # kinova: continuous joints, q on S¹

    def meddler(t, q, v):
        (q if argument == "q" else v).__imul__(0.0)
        return np.zeros(v.size)

    spec = {"method": method} | ({"dt": 0.01} if method in ("RK4", "semi-implicit-euler") else {})
    with pytest.raises(TorqueLawError, match=r"meddler.*must not modify q or v"):
        run_scene(_scene(robot, integrator=spec), torque_law=meddler)


def test_a_law_returning_v_itself_does_not_alias_the_state():
    tau = run_scene(_scene("chain:2"), torque_law=lambda t, q, v: v)
    assert tau.status == "completed"
