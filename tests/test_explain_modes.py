"""Modes of λmin and λmax: participations, body energy shares, against independent sums."""

from __future__ import annotations

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.explain.bodies import body_names
from gimwatch.explain.modes import gim_modes
from gimwatch.model.chains import chain_spec
from gimwatch.model.robots import chain_robot, load_robot


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_shares_sum_to_one_and_energies_add_up_to_the_eigenvalue(name):
    robot = load_robot(name)
    q = np.random.default_rng(0).uniform(-1, 1, robot.nq)
    modes = gim_modes(robot, q)
    M = pin.crba(robot.model, robot.model.createData(), q)
    w = np.linalg.eigvalsh(M)
    assert modes.kappa == pytest.approx(w[-1] / w[0], rel=1e-12)
    for mode in (modes.lowest, modes.highest):
        v = np.array(mode.vector)
        assert v @ M @ v == pytest.approx(mode.eigenvalue, rel=1e-12)
        assert sum(p for _, p in mode.joints) == pytest.approx(1.0, abs=1e-12)
        assert sum(s for _, s in mode.bodies) == pytest.approx(1.0, abs=1e-12)
        assert all(s >= -1e-12 for _, s in mode.bodies)


def test_body_energy_equals_a_model_with_only_that_body():
    """Energy share of body b = vᵀ M_b v / vᵀ M v, with M_b the CRBA of a model in which
    every other body's inertia is zero (an independent route to ½ vᵀ M_b v)."""
    robot = load_robot("ur5")
    q = np.array([0.3, -0.7, 1.1, 0.2, -0.4, 0.9])
    modes = gim_modes(robot, q)
    v = np.array(modes.lowest.vector)
    total = modes.lowest.eigenvalue
    shares = dict(modes.lowest.bodies)
    for j in range(1, robot.model.njoints):
        model = pin.Model(robot.model)
        for k in range(1, model.njoints):
            if k != j:
                model.inertias[k] = pin.Inertia.Zero()
        Mb = pin.crba(model, model.createData(), q)
        name = body_names(robot)[j - 1]
        assert shares[name] == pytest.approx(v @ Mb @ v / total, rel=1e-10, abs=1e-14)


def test_paper_chain_highest_mode_swings_the_chain_about_its_base():
    """The paper's straight 10-link chain: λmax's mode swings the whole chain about its
    base (joint 1 participates most, the tip link holds most of its energy)."""
    modes = gim_modes(chain_robot(chain_spec(10)), np.zeros(10))
    assert modes.highest.joints[0][0] == "joint_01"
    assert modes.highest.bodies[0][0] == "link_10"  # the tip moves fastest in a swing
