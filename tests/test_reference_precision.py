"""The mpmath references keep the digits they claim: 15 and 30 digits are not enough, 50 are.

The hard part of q̈ = M⁻¹ (τ − b(q, v)) for a reference is cancellation: with τ the float64
rounding of the bias b itself (computed at 80 digits), τ − b is ~1e-16·|b|, so every digit the
reference loses in b or in the solve shows in q̈. On the stress cases below (κ up to 8e19),
30 digits give relative q̈ errors of 3.5e-15 (planar closed form) and 8.3e-12 (tree ABA), 15
digits give no digit at all, and 50 digits (the default, what the stress suite uses) agree
with 100 digits to the last bit. mpmath's arithmetic is deterministic, so these margins hold
on any machine. The planar and tree references, written independently, agree to the last bit
on the same cancellation case.
"""

import mpmath
import numpy as np
import pytest

from gimwatch.denoc.tree import read_body_tree
from gimwatch.stress.cases import CASES
from gimwatch.stress.reference_planar import PlanarChainReference
from gimwatch.stress.reference_tree import TreeReference


def _relative(a, b):
    return float(np.linalg.norm(a - b) / np.linalg.norm(b))


def _case(name):
    case = CASES[name]
    robot, q = case.build()
    v = np.random.default_rng(0).uniform(-1.0, 1.0, robot.nv)
    model = robot.model
    index = {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)}
    tree = read_body_tree(robot.urdf_xml)

    def planar(dps=None):
        kwargs = {} if dps is None else {"dps": dps}
        return PlanarChainReference(case.spec, gravity_m_s2=case.gravity_m_s2[:2], **kwargs)

    def tree_ref(dps=None):
        kwargs = {} if dps is None else {"dps": dps}
        return TreeReference(tree, index, index, gravity=case.gravity_m_s2, **kwargs)

    return q, v, planar, tree_ref


def _solve(reference, q, v, tau):
    try:
        return reference.forward_dynamics(q, v, tau)
    except ZeroDivisionError:  # mpmath: "matrix is numerically singular" at low precision
        return np.full(len(tau), np.nan)


def test_planar_reference_needs_its_fifty_digits():
    q, v, planar, _ = _case("tapered-30")
    tau = np.array([float(x) for x in planar(80).bias(q, v)])
    truth = planar(100).forward_dynamics(q, v, tau)
    np.testing.assert_allclose(planar().forward_dynamics(q, v, tau), truth, rtol=1e-15, atol=0)
    assert not _relative(_solve(planar(30), q, v, tau), truth) <= 1e-15
    assert not _relative(_solve(planar(15), q, v, tau), truth) <= 1e-3
    assert mpmath.mp.dps == 15  # the working precision is restored


def test_tree_reference_needs_its_fifty_digits():
    q, v, _, tree = _case("tapered-30")
    tau = np.array([float(x) for x in tree(80).inverse_dynamics(q, v, np.zeros(q.size))])
    truth = tree(100).forward_dynamics(q, v, tau)
    np.testing.assert_allclose(tree().forward_dynamics(q, v, tau), truth, rtol=1e-15, atol=0)
    assert not _relative(_solve(tree(30), q, v, tau), truth) <= 1e-13
    assert not _relative(_solve(tree(15), q, v, tau), truth) <= 1e-3
    assert mpmath.mp.dps == 15


@pytest.mark.parametrize("name", ["heavy-root-20", "tapered-mass-30"])
def test_planar_and_tree_references_agree_to_the_last_bit_under_cancellation(name):
    q, v, planar, tree = _case(name)
    tau = np.array([float(x) for x in tree(80).inverse_dynamics(q, v, np.zeros(q.size))])
    a_tree = tree().forward_dynamics(q, v, tau)
    a_planar = planar().forward_dynamics(q, v, tau)
    np.testing.assert_allclose(a_tree, a_planar, rtol=1e-15, atol=0)
    # the comparison resolves the references' digits: at 20 digits they would not agree
    assert not _relative(_solve(tree(20), q, v, tau), a_planar) <= 1e-6


def _max_relative(values, truth):
    """max |x − t| / max |t| over matching entries (mpmath numbers), as a float."""
    scale = max(abs(t) for t in truth)
    return float(max(abs(x - t) for x, t in zip(values, truth, strict=True)) / scale)


def test_planar_mass_matrix_keeps_fifty_digits():
    """M(q) itself, not only q̈: tapered-30 (κ ≈ 8e19, so κ·eps ≈ 2e4).

    Entries at d digits carry ~10^−d relative error: measured 3e-16 (15), 3e-31 (30),
    below 1e-50 (50) against 100 digits. The tolerance 1e-40 sits between 30 and 50 digits
    by ten orders each way. κ of this M happens to be well conditioned in its entries (a
    15-digit M already gives λmin to 4e-16), so κ alone could not tell 15 digits from 50.
    """
    q, _, planar, _ = _case("tapered-30")
    truth = list(planar(100).gim(q))
    assert _max_relative(list(planar().gim(q)), truth) <= 1e-40
    for digits in (15, 30):
        assert not _max_relative(list(planar(digits).gim(q)), truth) <= 1e-40, digits
    with mpmath.workdps(120):  # κ from the 50-digit M, eigenvalues at 120 digits
        values = sorted(mpmath.eigsy(mpmath.matrix(planar().gim(q)), eigvals_only=True))
        exact = sorted(mpmath.eigsy(mpmath.matrix(planar(100).gim(q)), eigvals_only=True))
        assert abs(values[0] / exact[0] - 1) <= 1e-40
        assert values[-1] / values[0] > 1e19  # the case is as ill-conditioned as stated


def test_tree_aba_keeps_fifty_digits_in_mpmath():
    """The tree reference's unrounded q̈ (``forward_dynamics_mp``) on tapered-30 (κ ≈ 8e19).

    No cancellation is set up here (τ random): the 50-digit q̈ agrees with the 100-digit one
    to 1e-40 of its size, 15 and 30 digits do not (measured 2.1e-16 and 3.9e-31). The float64
    rounding of ``forward_dynamics`` would hide this; the mpmath values do not.
    """
    q, v, _, tree = _case("tapered-30")
    tau = np.random.default_rng(4).uniform(-1.0, 1.0, q.size)
    reference = tree(100)
    with mpmath.workdps(100):
        a = reference.forward_dynamics_mp(q, v, tau)
    for digits, ok in ((None, True), (30, False), (15, False)):
        with mpmath.workdps(100):
            a_d = tree(digits).forward_dynamics_mp(q, v, tau)
            error = _max_relative(a_d, a)
        assert (error <= 1e-40) is ok, (digits, error)
