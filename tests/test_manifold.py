"""Continuous joints and floating bases in every integrator (local coordinates on the manifold).

Robots: kinova (example-robot-data: three continuous joints, nq = 9, nv = 6) and solo12 on
a floating base (free-flyer + 12 joints, nq = 19, nv = 18). Energies are recomputed
independently of the simulation's own energy: ½ vᵀ M v with M from Pinocchio's CRBA, and
the potential −m_total g · c from the centre of mass c (Pinocchio's ``centerOfMass``).
"""

from __future__ import annotations

import dataclasses
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.model.robots import load_robot
from gimwatch.simulation.integrators import INTEGRATORS
from gimwatch.simulation.scene import load_scene, parse_scene
from gimwatch.simulation.simulate import Simulation, run_scene

SCENES = Path(__file__).resolve().parents[1] / "gimwatch" / "scenes"
G = np.array([0.0, 0.0, -9.81])
GRAVITY = {"gravity": {"vector": G.tolist()}}
KINOVA_V = {"j2s6s200_joint_1": 1.0, "j2s6s200_joint_3": -1.5}
SOLO_V = [0.0, 0.0, 0.3, 0.5, -1.0, 2.0] + [1.0] * 12
ROBOTS = {
    "continuous": ("kinova", "fixed", KINOVA_V),
    "floating": ("solo12", "floating", SOLO_V),
}
#: Settings per method and the relative energy drift each must stay under over 0.2 s.
METHODS = {
    "RK45": ({"rtol": 1e-10, "atol": 1e-10}, 1e-8),
    "DOP853": ({"rtol": 1e-10, "atol": 1e-10}, 1e-8),
    "Radau": ({"rtol": 1e-10, "atol": 1e-10}, 1e-8),
    "LSODA": ({"rtol": 1e-10, "atol": 1e-10}, 1e-8),
    "RK4": ({"dt": 1e-3}, 1e-7),
    "semi-implicit-euler": ({"dt": 2e-4}, 1e-2),
}


def _scene(kind, method, duration=0.2, **extra):
    robot, base, v = ROBOTS[kind]
    settings, _ = METHODS[method]
    table = {
        "robot": robot,
        "base": base,
        "duration": duration,
        "sample": 0.05,
        "q": 0.0,
        "v": v,
        "effects": GRAVITY,
        "integrator": {"method": method, **settings},
        **extra,
    }
    return parse_scene(table, source="m.toml")


def independent_energy(model, q, v):
    """½ vᵀ M(q) v (CRBA) − m g · c(q) (centre of mass), in J; not the code's energy."""
    data = model.createData()
    M = pin.crba(model, data, q)
    kinetic = 0.5 * v @ M @ v
    com = pin.centerOfMass(model, data, q)  # of the moving bodies; data.mass[0] is their mass
    return kinetic - data.mass[0] * G @ com, kinetic


def _relative_drift(model, run):
    pairs = zip(run.q, run.v, strict=True)
    energies = np.array([independent_energy(model, q, v) for q, v in pairs])
    total, kinetic = energies[:, 0], energies[:, 1]
    scale = max(abs(total[0]), kinetic.max())
    return float(np.abs(total - total[0]).max() / scale), total


def test_every_registered_integrator_is_covered():
    assert set(METHODS) == set(INTEGRATORS)


@pytest.mark.parametrize("kind", sorted(ROBOTS))
@pytest.mark.parametrize("method", sorted(METHODS))
def test_every_integrator_runs_continuous_joints_and_floating_bases(kind, method):
    run = run_scene(_scene(kind, method))
    assert run.status == "completed", run.message
    assert run.t[-1] == pytest.approx(0.2) and run.t.size == 5
    model = load_robot(ROBOTS[kind][0], floating=kind == "floating").model
    drift, total = _relative_drift(model, run)
    assert drift <= METHODS[method][1], (method, kind, drift)
    # the code's energy agrees with the independent one at every sample
    np.testing.assert_allclose(run.energy, total, rtol=0, atol=1e-9 * max(1.0, abs(total[0])))
    # every unit block stays on its manifold (no drift off the unit circle / sphere)
    if kind == "continuous":
        for joint in model.joints[1:]:
            if joint.nq == 2:
                norms = np.linalg.norm(run.q[:, joint.idx_q : joint.idx_q + 2], axis=1)
                np.testing.assert_allclose(norms, 1.0, atol=1e-12)
    else:
        np.testing.assert_allclose(np.linalg.norm(run.q[:, 3:7], axis=1), 1.0, atol=1e-12)


@pytest.mark.parametrize("kind", sorted(ROBOTS))
def test_methods_agree_with_a_tight_dop853_reference(kind):
    reference = run_scene(
        _scene(kind, "DOP853", integrator={"method": "DOP853", "rtol": 1e-13, "atol": 1e-13})
    )
    model = load_robot(ROBOTS[kind][0], floating=kind == "floating").model
    for method, tolerance in (("RK45", 1e-8), ("LSODA", 1e-7), ("RK4", 1e-8)):
        run = run_scene(_scene(kind, method))
        error = np.abs(pin.difference(model, run.q[-1], reference.q[-1])).max()
        assert error < tolerance, (method, error)


def test_rk4_is_fourth_order_on_a_floating_base():
    # in local coordinates with dΔq/dt = J(Δq)⁻¹ v; without J⁻¹ it would be second order
    reference = run_scene(
        _scene("floating", "DOP853", integrator={"method": "DOP853", "rtol": 1e-13, "atol": 1e-13})
    )
    model = load_robot("solo12", floating=True).model
    errors = []
    for dt in (5e-3, 2.5e-3):
        run = run_scene(_scene("floating", "RK4", integrator={"method": "RK4", "dt": dt}))
        errors.append(np.abs(pin.difference(model, run.q[-1], reference.q[-1])).max())
    order = np.log2(errors[0] / errors[1])
    assert 3.6 < order < 4.4, (errors, order)


def test_floating_base_centre_of_mass_falls_freely():
    # no contact and no joint torques: the centre of mass moves as c0 + ċ0 t + g t²/2
    run = run_scene(_scene("floating", "DOP853", duration=0.5))
    model = load_robot("solo12", floating=True).model
    data = model.createData()
    pin.centerOfMass(model, data, run.q[0], run.v[0])
    c0, cdot0 = data.com[0].copy(), data.vcom[0].copy()
    com = np.array([pin.centerOfMass(model, data, q) for q in run.q])
    expected = c0 + np.outer(run.t, cdot0) + np.outer(run.t**2 / 2, G)
    np.testing.assert_allclose(com, expected, atol=1e-9)


@pytest.mark.parametrize("name", ["kinova_swing.toml", "solo12_tumble.toml"])
def test_acceptance_scenes_keep_energy_with_dop853_from_q_zero(name):
    scene = load_scene(SCENES / name)
    assert scene.integrator.method == "DOP853" and scene.integrator.rtol == 1e-10
    scene = dataclasses.replace(scene, duration_s=0.5, sample_s=0.05, q=0.0)
    simulation = Simulation(scene)
    run = simulation.run()
    assert run.status == "completed", run.message
    drift, _ = _relative_drift(simulation.robot.model, run)
    assert drift <= 1e-8 and run.energy_drift() <= 1e-8, (drift, run.energy_drift())
