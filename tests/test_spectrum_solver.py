"""The watch's dense eigen-solve at every size regime against a spectrum known by construction."""

import numpy as np
import pytest

from gimwatch.watch.spectrum_solver import COMPILED_MAX_NV, UNBLOCKED_MAX_NV, SpectrumSolver

#: One size on each side of each switch of solver, and a robot-sized one.
SIZES = (7, COMPILED_MAX_NV, COMPILED_MAX_NV + 1, UNBLOCKED_MAX_NV, UNBLOCKED_MAX_NV + 1, 140)


def _known(n: int, kappa: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """M = Q diag(λ) Qᵀ with λ geometric from 1 to ``kappa``, Q a random orthogonal matrix."""
    rng = np.random.default_rng(seed)
    Q, _ = np.linalg.qr(rng.standard_normal((n, n)))
    values = np.geomspace(1.0, kappa, n)
    M = (Q * values) @ Q.T
    return (M + M.T) / 2.0, values


@pytest.mark.parametrize("n", SIZES)
def test_spectrum_and_kappa_are_the_constructed_ones_scaled_or_not(n):
    M, values = _known(n, 1e4, n)
    solver = SpectrumSolver(n)
    # the error of λ is about n eps λmax (backward stability), far below this tolerance
    for factor in (1.0, 2.0**-600, 2.0**600, 1e-300, 1e300):
        spectrum, scale = solver.scaled(M * factor)
        np.testing.assert_allclose(spectrum * scale / factor, values, rtol=1e-9)
        assert solver.ratio(M * factor) == pytest.approx(1e4, rel=1e-9)


@pytest.mark.parametrize("n", SIZES)
def test_a_bad_matrix_gives_nan_or_a_non_positive_spectrum_not_an_exception(n):
    M, _ = _known(n, 10.0, n)
    solver = SpectrumSolver(n)
    for bad in (np.nan, np.inf):
        broken = M.copy()
        broken[0, n - 1] = broken[n - 1, 0] = bad
        assert np.isnan(solver.ratio(broken))
    indefinite = M - 5.0 * np.eye(n)  # λmin = 1 - 5 < 0, diagonal still positive
    assert np.isnan(solver.ratio(indefinite))
    solved = solver.scaled(indefinite)
    assert solved is None or not solved[0][0] > 0.0


def test_each_size_regime_uses_its_solver():
    assert SpectrumSolver(COMPILED_MAX_NV)._syevd is None  # the numba kernel
    unblocked = SpectrumSolver(COMPILED_MAX_NV + 1)
    assert unblocked._lwork == 2 * (COMPILED_MAX_NV + 1) + 1  # LAPACK's minimal workspace
    assert SpectrumSolver(UNBLOCKED_MAX_NV + 1)._lwork > 2 * (UNBLOCKED_MAX_NV + 1) + 1
