"""Fast trajectories on the manifold checked against an independent integration.

gimwatch integrates continuous joints and floating bases in local coordinates around an
anchor that moves at every sample and, mid-piece, whenever ‖Δq‖∞ exceeds
``REANCHOR_NORM`` (1 rad or m). These tests move *several radians between samples* (a
kinova joint at 40 rad/s with samples every 0.1 s; a solo12 base tumbling at ~40 rad/s) so
that every piece re-anchors mid-way, and compare every recorded sample with the same motion
integrated independently:

* a different coordinate chart — continuous joints as plain angles θ (q = (cos θ, sin θ)),
  the free-flyer as position + a quaternion integrated in R⁴ by q̇ = ½ q ⊗ (0, ω) (the
  embedding, no local coordinates, no anchors, no pieces);
* one SciPy ``solve_ivp`` (DOP853) call over the whole run at rtol = atol = 1e-13 with dense
  output at the sample times;
* the same physics (Pinocchio's ABA with gravity, no torque), which is not under test here.

Accuracy: the scenes run DOP853 at rtol = atol = 1e-10 (the acceptance scenes' setting,
docs/scenes.md). Worst sample errors measured over 1 s: q 3.1e-10 and v 6.4e-10 (kinova),
q 9.4e-11 and v 4.5e-9 (solo12); the tolerances 3e-9 and 5e-8 leave a margin of ~8-10. A
sample recorded with the state of an earlier time is off by radians.

The motions are chosen *regular* (a wrist spin; a base spin about one axis with the legs
swinging): a multi-axis tumble or the kinova shoulder flung at 40 rad/s is chaotic here (the
difference between two correct integrations grows ~10× per 0.1 s), so no fixed tolerance
would separate a correct integrator from a wrong one there.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest
import scipy.integrate

from gimwatch.model.robots import load_robot
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene

G = np.array([0.0, 0.0, -9.81])
#: Sample errors allowed in q (rad or m, as ``pin.difference``) and v (rad/s or m/s).
TOLERANCE_Q, TOLERANCE_V = 3e-9, 5e-8


def _run(robot, base, q, v, duration=1.0, sample=0.1):
    table = {
        "robot": robot,
        "base": base,
        "duration": duration,
        "sample": sample,
        "q": q,
        "v": v,
        "effects": {"gravity": {"vector": G.tolist()}},
        "integrator": {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10},
    }
    run = run_scene(parse_scene(table, source="trajectory.toml"))
    assert run.status == "completed", run.message
    return run


def _aba(model, data, q, v):
    model.gravity.linear = G
    return pin.aba(model, data, q, v, np.zeros(model.nv))


def _reference(rhs, y0, times):
    solution = scipy.integrate.solve_ivp(
        rhs, (0.0, times[-1]), y0, method="DOP853", rtol=1e-13, atol=1e-13, t_eval=times
    )
    assert solution.success, solution.message
    return solution.y.T


# -- continuous joints as angles ------------------------------------------------------------
def _angle_chart(model):
    """q(θ) for a fixed-base model whose joints are revolute or continuous (one angle each)."""
    continuous = [j.nq == 2 for j in model.joints[1:]]

    def q_of(theta):
        parts = []
        for angle, is_continuous in zip(theta, continuous, strict=True):
            parts += [np.cos(angle), np.sin(angle)] if is_continuous else [angle]
        return np.array(parts)

    def theta_of(q):
        out, k = [], 0
        for is_continuous in continuous:
            out.append(np.arctan2(q[k + 1], q[k]) if is_continuous else q[k])
            k += 2 if is_continuous else 1
        return np.array(out)

    return q_of, theta_of


def test_kinova_continuous_joint_at_40_rad_s_matches_an_angle_chart_integration():
    v = {"j2s6s200_joint_4": 20.0, "j2s6s200_joint_6": -40.0}
    run = _run("kinova", "fixed", 0.0, v)
    model = load_robot("kinova").model
    assert any(j.nq == 2 for j in model.joints[1:])
    data = model.createData()
    q_of, theta_of = _angle_chart(model)
    nv = model.nv

    def rhs(_t, y):
        theta, vel = y[:nv], y[nv:]
        return np.concatenate((vel, _aba(model, data, q_of(theta), vel)))

    theta0 = theta_of(run.q[0])
    reference = _reference(rhs, np.concatenate((theta0, run.v[0])), run.t)
    # the fast joint turns ~4 rad between samples (several mid-piece re-anchorings)
    # the wrist turns ~4 rad between samples (several mid-piece re-anchorings per piece)
    assert np.abs(np.diff(reference[:, 5])).min() > 3.0
    for k, t in enumerate(run.t):
        q_ref = q_of(reference[k, :nv])
        error_q = np.abs(pin.difference(model, run.q[k], q_ref)).max()
        error_v = np.abs(run.v[k] - reference[k, nv:]).max()
        assert error_q < TOLERANCE_Q, (t, error_q)
        assert error_v < TOLERANCE_V, (t, error_v)


# -- a free-flyer with its quaternion integrated in R⁴ ------------------------------------
def _quaternion_rate(quat_xyzw, omega_local):
    """q̇ = ½ q ⊗ (ω, 0) for a unit quaternion (x, y, z, w) and a body-frame rate ω."""
    x, y, z, w = quat_xyzw
    wx, wy, wz = omega_local
    return 0.5 * np.array(
        [
            w * wx + y * wz - z * wy,
            w * wy + z * wx - x * wz,
            w * wz + x * wy - y * wx,
            -x * wx - y * wy - z * wz,
        ]
    )


def test_solo12_base_tumbling_matches_a_quaternion_embedding_integration():
    omega = [40.0, 0.0, 0.0]  # rad/s in the base frame: > 2 rad between samples
    v = [0.5, -0.3, 2.0, *omega] + [3.0, -2.0, 1.0] * 4
    run = _run("solo12", "floating", 0.0, v)
    model = load_robot("solo12", floating=True).model
    assert model.joints[1].shortname() == "JointModelFreeFlyer"
    data = model.createData()
    nq = model.nq

    def rhs(_t, y):
        q, vel = y[:nq].copy(), y[nq:]
        q[3:7] /= np.linalg.norm(q[3:7])
        rotation = pin.Quaternion(q[6], q[3], q[4], q[5]).toRotationMatrix()
        q_dot = np.concatenate((rotation @ vel[:3], _quaternion_rate(q[3:7], vel[3:6]), vel[6:]))
        return np.concatenate((q_dot, _aba(model, data, q, vel)))

    reference = _reference(rhs, np.concatenate((run.q[0], run.v[0])), run.t)
    turned = [
        np.linalg.norm(
            pin.log3(
                pin.Quaternion(*reference[k, [6, 3, 4, 5]]).toRotationMatrix().T
                @ pin.Quaternion(*reference[k + 1, [6, 3, 4, 5]]).toRotationMatrix()
            )
        )
        for k in range(run.t.size - 1)
    ]
    assert min(turned) > 2.0, turned  # the base turns more than 2 rad between samples
    for k, t in enumerate(run.t):
        q_ref = reference[k, :nq].copy()
        q_ref[3:7] /= np.linalg.norm(q_ref[3:7])
        error_q = np.abs(pin.difference(model, run.q[k], q_ref)).max()
        error_v = np.abs(run.v[k] - reference[k, nq:]).max()
        assert error_q < TOLERANCE_Q, (t, error_q)
        assert error_v < TOLERANCE_V, (t, error_v)


@pytest.mark.parametrize("sample", [0.1, 0.037])
def test_kinova_samples_do_not_depend_on_the_sample_period(sample):
    # the same motion sampled at two periods agrees at common times with the reference run
    run = _run("kinova", "fixed", 0.0, {"j2s6s200_joint_6": 40.0}, duration=0.5, sample=sample)
    model = load_robot("kinova").model
    data = model.createData()
    q_of, theta_of = _angle_chart(model)
    nv = model.nv

    def rhs(_t, y):
        return np.concatenate((y[nv:], _aba(model, data, q_of(y[:nv]), y[nv:])))

    reference = _reference(rhs, np.concatenate((theta_of(run.q[0]), run.v[0])), run.t)
    errors = [
        np.abs(pin.difference(model, run.q[k], q_of(reference[k, :nv]))).max()
        for k in range(run.t.size)
    ]
    assert max(errors) < TOLERANCE_Q, errors
