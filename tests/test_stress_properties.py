"""Property tests over random chains (hypothesis, derandomized): the GIM's invariants.

For any chain of rods with positive radii (so every revolute joint moves some inertia),
any joint axes and types and any configuration: M is symmetric positive definite, κ ≥ δ ≥ 1
(λmin ≤ M_ii ≤ λmax), DeNOC's M equals Pinocchio's CRBA and the O(n) diagonal equals
diag(CRBA).
"""

import numpy as np
import pinocchio as pin
import scipy.linalg
from hypothesis import given, settings
from hypothesis import strategies as st

from gimwatch.crosscheck import denoc_model
from gimwatch.metrics.conditioning import condition_number, diagonal_ratio
from gimwatch.model.chains import chain_spec
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import chain_robot


@st.composite
def chains(draw):
    n = draw(st.integers(1, 8))
    per_link = st.lists
    log_mass = draw(per_link(st.floats(-2, 2), min_size=n, max_size=n))
    lengths = draw(per_link(st.floats(0.05, 3.0), min_size=n, max_size=n))
    radii = draw(per_link(st.floats(0.005, 0.2), min_size=n, max_size=n))
    axes = draw(per_link(st.sampled_from("xyz"), min_size=n, max_size=n))
    kinds = draw(per_link(st.sampled_from(["revolute", "prismatic"]), min_size=n, max_size=n))
    q = draw(per_link(st.floats(-np.pi, np.pi), min_size=n, max_size=n))
    spec = chain_spec(
        n,
        mass_kg=10.0 ** np.array(log_mass),
        length_m=lengths,
        radius_m=radii,
        axes=axes,
        joint_types=kinds,
    )
    # prismatic joints stay within their limits (± half the rod)
    q = [
        x if k == "revolute" else x / np.pi * l / 2
        for x, k, l in zip(q, kinds, lengths, strict=True)
    ]
    return spec, np.array(q)


@settings(max_examples=60, derandomize=True, deadline=None)
@given(chains())
def test_gim_invariants_hold_on_random_chains(chain):
    spec, q = chain
    robot = chain_robot(spec)
    data = robot.new_data()
    upper = np.array(pin.crba(robot.model, data, q))
    M = np.triu(upper) + np.triu(upper, 1).T
    M_denoc = denoc_model(robot).gim(q)
    scale = np.abs(M).max()
    # symmetry of the independently computed DeNOC matrix, and DeNOC = CRBA
    np.testing.assert_allclose(M_denoc, M_denoc.T, rtol=0, atol=1e-13 * scale)
    np.testing.assert_allclose(M_denoc, M, rtol=0, atol=1e-12 * scale)
    # positive definite: Cholesky succeeds and the smallest eigenvalue is positive
    scipy.linalg.cholesky(M, lower=True)
    assert np.linalg.eigvalsh(M)[0] > 0
    kappa, delta = condition_number(M), diagonal_ratio(M)
    assert delta >= 1.0
    assert kappa >= delta * (1 - 1e-9), (kappa, delta)
    # the O(n) diagonal from composite inertias equals diag(CRBA)
    np.testing.assert_allclose(gim_diagonal(robot, q), np.diag(M), rtol=1e-10, atol=1e-14 * scale)
    np.testing.assert_allclose(
        denoc_model(robot).gim_diagonal(q), np.diag(M), rtol=1e-10, atol=1e-14 * scale
    )
