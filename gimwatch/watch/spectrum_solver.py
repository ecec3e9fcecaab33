"""The dense symmetric eigen-solve of the watch's κ, by the solver measured fastest at its size.

κ = λmax / λmin (Shah & Saha 2013, Eq. 6) of a robot-sized M is one LAPACK ``syevd`` without
eigenvectors: a reduction to tridiagonal form (O(n³), nearly all the time) and the
tridiagonal eigenvalues (``sterf``, O(n²)). How it is called decides its cost on small
matrices (2-core benchmark host, one BLAS thread; `gimwatch bench watch_overhead`):

* n ≤ `COMPILED_MAX_NV`: the numba kernel `gimwatch.watch.kernels.scaled_spectrum`, no
  Python wrapper at all (LAPACK reduces these sizes unblocked whatever the workspace);
* n ≤ `UNBLOCKED_MAX_NV`: SciPy's ``dsyevd`` given its minimal workspace, which keeps the
  tridiagonal reduction unblocked. The blocked one, which NumPy's ``eigvalsh`` and numba ask
  for with their optimal workspace, is about 1.25× slower at n = 35 (64 against 82 µs at
  n = 33) and only pays from about n = 100;
* larger n: ``dsyevd`` with its optimal workspace (the blocked reduction).

Every path scales M by s = 2^k first when its entries leave [2^-400, 2^400] (see
`gimwatch.watch.kernels.spectrum_scale`), so a finite M keeps a finite spectrum.
"""

from __future__ import annotations

import numpy as np

from gimwatch.watch import kernels

__all__ = ["COMPILED_MAX_NV", "UNBLOCKED_MAX_NV", "SpectrumSolver"]

#: Up to this n the numba kernel solves (OpenBLAS reduces n ≤ 32 unblocked in any case).
COMPILED_MAX_NV = 32
#: Up to this n ``dsyevd`` gets its minimal workspace: the unblocked reduction is faster here.
UNBLOCKED_MAX_NV = 100


class SpectrumSolver:
    """Ascending eigenvalues of M / s for n x n matrices, s a power of two (1 unless needed).

    Args:
        n: The size of the matrices it will solve.

    A bad M (not finite, not positive definite) gives a NaN or non-positive λmin, or None,
    never an exception: the caller's checked path names the problem.
    """

    def __init__(self, n: int) -> None:
        self.n = int(n)
        self._syevd = None
        if self.n > COMPILED_MAX_NV:
            from scipy.linalg import lapack  # 0.2 s to import: only watches that use it pay

            self._syevd = lapack.dsyevd
            if self.n <= UNBLOCKED_MAX_NV:
                self._lwork = 2 * self.n + 1  # LAPACK's minimum without eigenvectors
            else:
                self._lwork = int(lapack.dsyevd_lwork(self.n, compute_v=0, lower=1)[0])

    def scaled(self, M: np.ndarray) -> tuple[np.ndarray, float] | None:
        """(eigenvalues of M / s ascending, s), or None when LAPACK refuses M or fails."""
        if self._syevd is None:
            try:
                return kernels.scaled_spectrum(M)
            except np.linalg.LinAlgError:  # numba's check: NaN or inf off the diagonal
                return None
        scale = kernels.spectrum_scale(M)
        if not scale > 0.0:
            return None
        if scale != 1.0:
            M = M * (1.0 / scale)
        # M.T: the Fortran-ordered view of a symmetric C-ordered M, so nothing is transposed
        values, _, info = self._syevd(M.T, compute_v=0, lower=1, lwork=self._lwork)
        return (values, scale) if info == 0 else None

    def ratio(self, M: np.ndarray) -> float:
        """κ = λmax / λmin; NaN unless M is finite and positive definite as solved."""
        if self._syevd is None:
            try:
                return kernels.spectrum_ratio(M)
            except np.linalg.LinAlgError:
                return np.nan
        solved = self.scaled(M)
        return np.nan if solved is None else kernels.positive_ratio(solved[0])
