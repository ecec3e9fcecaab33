"""The κ tracker's Krylov engine against LAPACK (NumPy's eigh)."""

import numpy as np
import pytest
from krylov_reference import leading_reference

from gimwatch.metrics.tracker.krylov import MAX_BASIS, Workspace, _eigh, leading_callable


@pytest.mark.parametrize("m", [1, 2, 3, 5, 8, 12, 16])
def test_small_symmetric_eigensolver_matches_lapack(m):
    """Cyclic Jacobi (m ≤ 12; LAPACK above): eigenvalues ascending, orthonormal vectors,
    on a matrix graded over 16 orders of magnitude."""
    rng = np.random.default_rng(m)
    basis = np.linalg.qr(rng.standard_normal((m, m)))[0]
    spectrum = np.sort(10.0 ** rng.uniform(-8, 8, m) * rng.choice([-1, 1], m))
    A = (basis * spectrum) @ basis.T
    H = np.zeros((m + 2, m + 2))
    H[:m, :m] = A
    values, vectors = _eigh(H, m)
    reference = np.linalg.eigvalsh(A)
    scale = np.abs(reference).max()
    np.testing.assert_allclose(values, reference, rtol=0, atol=1e-14 * scale)
    assert np.all(np.diff(values) >= 0)
    np.testing.assert_allclose(vectors.T @ vectors, np.eye(m), rtol=0, atol=1e-13)
    np.testing.assert_allclose(A @ vectors, vectors * values, rtol=0, atol=1e-13 * scale)


def test_leading_pair_through_thick_restarts():
    """A cold start with a clustered top (gaps 1e-3) fills the basis and restarts several
    times; the leading Ritz pair still meets the tolerance, counted products add up."""
    n = 200
    rng = np.random.default_rng(7)
    basis = np.linalg.qr(rng.standard_normal((n, n)))[0]
    spectrum = np.linspace(0.1, 1.0, n)
    spectrum[-4:] = [1.997, 1.998, 1.999, 2.0]
    A = (basis * spectrum) @ basis.T
    calls = []

    def apply(x):
        calls.append(1)
        return A @ x

    ritz = np.empty((2, n))
    theta, estimate, ok, used = leading_callable(
        apply, rng.standard_normal((1, n)), Workspace(n), ritz, rtol=1e-12, budget=2000, keep=2
    )
    assert ok and used == len(calls) > MAX_BASIS  # restarted at least once
    assert theta == pytest.approx(2.0, rel=1e-11)
    assert estimate <= 1e-12
    assert abs(ritz[-1] @ basis[:, -1]) == pytest.approx(1.0, abs=1e-5)


@pytest.mark.parametrize(("keep", "starts", "budget"), [(2, 1, 2000), (8, 3, 2000), (2, 1, 30)])
def test_engine_takes_the_steps_of_the_former_python_twin(keep, starts, budget):
    """The reverse-communication engine against the plain loop it replaced
    (tests/krylov_reference.py): the same products in the same order, the same Ritz pair, on a
    clustered top, through restarts and when the budget runs out."""
    n = 150
    rng = np.random.default_rng(keep + starts)
    basis = np.linalg.qr(rng.standard_normal((n, n)))[0]
    spectrum = np.linspace(0.1, 1.0, n)
    spectrum[-3:] = [1.998, 1.999, 2.0]
    A = (basis * spectrum) @ basis.T
    block = rng.standard_normal((starts, n))
    runs = []
    for engine in (leading_callable, leading_reference):
        seen = []

        def apply(x, seen=seen):
            seen.append(x.copy())
            return A @ x

        ritz = np.empty((keep, n))
        found = engine(apply, block, Workspace(n), ritz, rtol=1e-12, budget=budget, keep=keep)
        runs.append((found, np.array(seen), ritz))
    (new, new_seen, new_ritz), (old, old_seen, old_ritz) = runs
    assert new[2:] == old[2:]  # converged, products used
    assert new[0] == pytest.approx(old[0], rel=1e-14)
    np.testing.assert_allclose(new_seen, old_seen, rtol=0, atol=1e-12)
    np.testing.assert_allclose(new_ritz, old_ritz, rtol=0, atol=1e-10)
