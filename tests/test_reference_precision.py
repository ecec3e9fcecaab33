"""The mpmath references keep the digits they claim: 15 and 30 digits are not enough, 50 are.

The hard part of q̈ = M⁻¹ (τ − b(q, v)) for a reference is cancellation: with τ the float64
rounding of the bias b itself (computed at 80 digits), τ − b is ~1e-16·|b|, so every digit the
reference loses in b or in the solve shows in q̈. On the stress cases below (κ up to 8e19),
30 digits give relative q̈ errors of 3.5e-15 (planar closed form) and 8.3e-12 (tree ABA), 15
digits give no digit at all, and 50 digits (the default, what the stress suite uses) agree
with 100 digits to the last bit. mpmath's arithmetic is deterministic, so these margins hold
on any machine. The planar and tree references, written independently, agree to the last bit
on the same cancellation case. The tree reference's ABA is also held against its RNEA solved at
100 digits (a different algorithm), so an ABA that ignored its ``dps`` cannot pass by being
wrong in the same way at 100 digits.
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

    def tree_ref(dps=None, gravity=case.gravity_m_s2):
        kwargs = {} if dps is None else {"dps": dps}
        return TreeReference(tree, index, index, gravity=gravity, **kwargs)

    return q, v, planar, tree_ref


def _rnea_solution(tree_ref, q, v, tau, dps=100):
    """q̈ = M⁻¹ (τ − b) at ``dps`` digits from the tree reference's RNEA alone, not its ABA.

    M column by column (RNEA without gravity at v = 0, q̈ = e_j), b = RNEA(q, v, 0), then
    mpmath's LU solve: a different algorithm from the ABA it checks (Featherstone Table 5.1,
    not 7.1), so a precision lost in the ABA alone cannot hide in both sides.
    """
    n = len(tau)
    inertia_only = tree_ref(dps, gravity=(0.0, 0.0, 0.0))
    with mpmath.workdps(dps):
        M = mpmath.matrix(n, n)
        for j in range(n):
            column = inertia_only.inverse_dynamics(q, np.zeros(n), np.eye(n)[j])
            for i in range(n):
                M[i, j] = column[i]
        bias = tree_ref(dps).inverse_dynamics(q, v, np.zeros(n))
        rhs = mpmath.matrix([mpmath.mpf(float(t)) - b for t, b in zip(tau, bias, strict=True)])
        solution = mpmath.lu_solve(M, rhs)
        return [solution[i] for i in range(n)]


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
    """q̈ under cancellation (τ = b rounded to float64) on tapered-30, κ ≈ 8e19.

    The truth is the RNEA solve at 100 digits (`_rnea_solution`), not the ABA at 100 digits:
    an ABA that ignored its ``dps`` would give the same wrong digits at 100 and at 50. The
    default agrees with it to 1e-15 (far below κ·eps ≈ 2e4); 30 digits miss by 8e-12.
    """
    q, v, _, tree = _case("tapered-30")
    tau = np.array([float(x) for x in tree(80).inverse_dynamics(q, v, np.zeros(q.size))])
    truth = np.array([float(x) for x in _rnea_solution(tree, q, v, tau)])
    np.testing.assert_allclose(tree().forward_dynamics(q, v, tau), truth, rtol=1e-15, atol=0)
    np.testing.assert_allclose(tree(100).forward_dynamics(q, v, tau), truth, rtol=1e-15, atol=0)
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


@pytest.mark.parametrize("name", ["tapered-30", "mixed-spatial-24"])
def test_tree_aba_keeps_fifty_digits_in_mpmath(name):
    """The tree reference's unrounded q̈ (``forward_dynamics_mp``) against two truths.

    tapered-30 (planar, κ ≈ 8e19) and mixed-spatial-24 (axes z, y, x, every third joint
    prismatic). No cancellation is set up here (τ random): the 50-digit q̈ agrees with the
    100-digit ABA and with the 100-digit RNEA solve (`_rnea_solution`, independent of the ABA)
    to 1e-40 of its size, 15 and 30 digits do not (measured 2e-16 / 1.5e-15 and 3e-31 /
    5e-31; 50 digits: 2e-51 / 9e-51). The float64 rounding of ``forward_dynamics`` would hide
    this; the mpmath values do not. The two truths agree to 1e-98.
    """
    q, v, _, tree = _case(name)
    tau = np.random.default_rng(4).uniform(-1.0, 1.0, q.size)
    with mpmath.workdps(100):
        aba = tree(100).forward_dynamics_mp(q, v, tau)
        rnea = _rnea_solution(tree, q, v, tau)
        assert _max_relative(aba, rnea) <= 1e-95
    for digits, ok in ((None, True), (30, False), (15, False)):
        with mpmath.workdps(100):
            a_d = tree(digits).forward_dynamics_mp(q, v, tau)
            errors = (_max_relative(a_d, aba), _max_relative(a_d, rnea))
        assert (errors[0] <= 1e-40, errors[1] <= 1e-40) == (ok, ok), (digits, errors)
    assert mpmath.mp.dps == 15
