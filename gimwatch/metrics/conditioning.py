"""Conditioning metrics of a symmetric positive-definite matrix (a GIM or its diagonal).

Pure NumPy/SciPy: this module knows no robot. Every function that takes a full matrix
checks it first (square, finite, symmetric, positive definite) and raises
[`ConditioningError`][gimwatch.errors.ConditioningError] otherwise.

Metrics (Shah & Saha 2013):

* [`condition_number`][gimwatch.metrics.conditioning.condition_number] — κ₂ = λmax / λmin (Eq. 6),
  from a symmetric eigensolver.
* [`diagonal_ratio`][gimwatch.metrics.conditioning.diagonal_ratio] — δ = max_i M_ii / min_i M_ii
  (Sec. 4); free once diag M is known.
* [`ScaledDiagonalRatio`][gimwatch.metrics.conditioning.ScaledDiagonalRatio] — αδ with α = κ(t0) /
  δ(t0) (Eq. 15).
* [`pivot_ratio_forward`][gimwatch.metrics.conditioning.pivot_ratio_forward] /
  [`pivot_ratio_backward`][gimwatch.metrics.conditioning.pivot_ratio_backward] — max/min pivot of
  Gaussian elimination without pivoting (Sec. 4, Fig. 4), eliminating from the first coordinate
  (LDLᵀ, the paper's order) or from the last (UDUᵀ, the order of Pinocchio's ``cholesky.decompose``
  and of the O(n) forward-dynamics recursions).
* [`condition_estimate_1norm`][gimwatch.metrics.conditioning.condition_estimate_1norm] — LAPACK
  ``pocon``'s estimate of κ₁ from the Cholesky factor, a cheap baseline (O(n²) after the O(n³)
  factorisation).
"""

from __future__ import annotations

import warnings

import numpy as np
import numpy.typing as npt

from gimwatch.errors import ConditioningError, IllConditionedWarning, InputError

__all__ = [
    "ScaledDiagonalRatio",
    "check_gim",
    "condition_estimate_1norm",
    "condition_number",
    "diagonal_ratio",
    "eigenpairs",
    "eigenvalues",
    "extreme_ratio",
    "ldlt_pivots",
    "pivot_ratio_backward",
    "pivot_ratio_forward",
    "udut_pivots",
]

#: Relative asymmetry max|M - Mᵀ| / max|M| accepted as round-off.
SYMMETRY_RTOL = 1e-10


def check_gim(matrix: npt.ArrayLike) -> np.ndarray:
    """Return ``matrix`` as a float array after checking it is a valid GIM.

    Raises:
        ConditioningError: Not real numbers, not square, empty, not finite, not symmetric
            (beyond ``SYMMETRY_RTOL``) or not positive definite.
    """
    M = _real_array(matrix, "the GIM")
    if M.ndim != 2 or M.shape[0] != M.shape[1] or M.shape[0] == 0:
        raise ConditioningError(f"the GIM must be a non-empty square matrix, got shape {M.shape}")
    if not np.all(np.isfinite(M)):
        raise ConditioningError("the GIM must be finite, got NaN or inf entries")
    scale = np.max(np.abs(M))
    asymmetry = np.max(np.abs(M - M.T))
    if asymmetry > SYMMETRY_RTOL * scale:
        raise ConditioningError(
            f"the GIM must be symmetric, got max|M - M^T| / max|M| = {asymmetry / scale:.3g}"
        )
    if np.any(np.diag(M) <= 0):
        k = int(np.argmin(np.diag(M)))
        raise ConditioningError(
            f"the GIM must be positive definite, got diagonal entry {k} = {M[k, k]:.6g}"
        )
    return M


def _cholesky_lower(M: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.cholesky(M)  # LAPACK potrf; NumPy's, so scipy.linalg loads only for pocon
    except np.linalg.LinAlgError as exc:
        raise ConditioningError(f"the GIM must be positive definite ({exc})") from exc


def eigenvalues(matrix: npt.ArrayLike) -> np.ndarray:
    """Eigenvalues of the GIM in ascending order (symmetric eigensolver, LAPACK).

    NumPy's ``syevd`` first: importing ``scipy.linalg`` costs about 0.2 s, more than a whole
    ``gimwatch analyze`` of a small robot otherwise. When κ nears 1/eps, λmin is round-off
    (about eps·λmax) and its sign depends on the LAPACK driver; a λmin ≤ 0 from ``syevd`` is
    recomputed with SciPy's ``syevr`` (the driver gimwatch used before) before M is declared
    not positive definite, so such numerically singular GIMs keep their former verdict.
    """
    values, scale = _scaled_eigenvalues(matrix)
    return values * scale


def _scaled_eigenvalues(matrix: npt.ArrayLike) -> tuple[np.ndarray, float]:
    """Eigenvalues of M / s (ascending) and s = 2^k <= max |M_ij| < 2^(k+1).

    Solving the scaled matrix keeps a finite M finite (``[[2, 1], [1, 2]] · 8e307``: κ = 3,
    where the unscaled solve overflows); a power of two scales without rounding.
    """
    M = check_gim(matrix)
    scale = float(np.ldexp(1.0, int(np.frexp(np.max(np.abs(M)))[1]) - 1))
    M = M / scale
    values = np.linalg.eigvalsh(M)
    if values[0] <= 0:
        import scipy.linalg

        values = scipy.linalg.eigvalsh(M, check_finite=False)
    if values[0] <= 0:
        raise ConditioningError(
            f"the GIM must be positive definite, got smallest eigenvalue {values[0] * scale:.6g}"
        )
    return values, scale


def eigenpairs(matrix: npt.ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Eigenvalues (ascending) and eigenvectors (columns) of the GIM (SciPy's ``eigh``).

    The eigenvalues are as LAPACK returns them: near κ = 1/eps the smallest may come out
    ≤ 0, which the caller judges ([`eigenvalues`][gimwatch.metrics.conditioning.eigenvalues] refuses
    it).

    Raises:
        ConditioningError: M is not a valid GIM.
    """
    import scipy.linalg

    return scipy.linalg.eigh(check_gim(matrix), check_finite=False)


def extreme_ratio(values: npt.ArrayLike) -> float:
    """Max / min of positive numbers: the one ratio behind κ, δ and the pivot ratios.

    κ₂ is the ratio of the extreme eigenvalues (Eq. 6), δ that of the diagonal (Sec. 4), a
    pivot ratio that of the pivots of Gaussian elimination (Fig. 4).
    """
    values = np.asarray(values, dtype=float)
    return float(values.max() / values.min())


def condition_number(matrix: npt.ArrayLike) -> float:
    """κ₂(M) = λmax / λmin (Shah & Saha 2013, Eq. 6).

    Round-off limits it: λmin is known only to about eps·λmax, so values near 1/eps
    (~4.5e15) carry no digits.
    """
    return extreme_ratio(_scaled_eigenvalues(matrix)[0])


def _real_array(value: npt.ArrayLike, what: str) -> np.ndarray:
    """``value`` as a float array; complex or non-numeric entries are a ConditioningError.

    A complex Hermitian matrix is not a GIM: casting it to float would drop its imaginary
    part (and NumPy only warns), giving a wrong κ.
    """
    try:
        array = np.asarray(value)
    except (TypeError, ValueError) as exc:  # ragged nested lists
        raise ConditioningError(f"{what} must be an array of real numbers ({exc})") from exc
    if array.dtype.kind == "O":  # Python numbers (Fraction, mpmath.mpf, ...)
        try:
            return array.astype(float)
        except (TypeError, ValueError) as exc:
            raise ConditioningError(f"{what} must hold real numbers ({exc})") from exc
    if array.dtype.kind not in "biuf":
        raise ConditioningError(f"{what} must hold real numbers, got {array.dtype.name} entries")
    return array.astype(float)


def _diagonal_of(matrix_or_diagonal: npt.ArrayLike) -> np.ndarray:
    array = _real_array(matrix_or_diagonal, "the GIM or its diagonal")
    diag = np.diag(array) if array.ndim == 2 else array
    if diag.ndim != 1 or diag.size == 0:
        raise ConditioningError(f"expected a GIM or its diagonal, got shape {array.shape}")
    if not np.all(np.isfinite(diag)) or np.any(diag <= 0):
        raise ConditioningError("the GIM's diagonal must be finite and positive")
    return diag


def diagonal_ratio(matrix_or_diagonal: npt.ArrayLike) -> float:
    """δ = max_i M_ii / min_i M_ii (Shah & Saha 2013, Sec. 4), from M or diag M.

    Since λmin <= M_ii <= λmax, δ is a lower bound of κ₂.
    """
    return extreme_ratio(_diagonal_of(matrix_or_diagonal))


class ScaledDiagonalRatio:
    """The scaled diagonal ratio αδ of Shah & Saha (2013), Eq. (15).

    α = κ(M₀) / δ(M₀) is fixed once, at the first matrix (t = 0); afterwards each call
    costs only the diagonal ratio. Calibrating again is refused so that α cannot be tuned
    after the fact.

    Examples:
        >>> import numpy as np
        >>> estimator = ScaledDiagonalRatio()
        >>> estimator.calibrate(np.diag([4.0, 1.0]))
        1.0
        >>> estimator(np.array([9.0, 1.0]))
        9.0
    """

    def __init__(self, alpha: float | None = None) -> None:
        if alpha is not None and not (np.isfinite(alpha) and alpha > 0):
            raise InputError("alpha", "finite and > 0", alpha)
        self._alpha = None if alpha is None else float(alpha)

    @property
    def alpha(self) -> float | None:
        """The scale α, or None before calibration."""
        return self._alpha

    @property
    def calibrated(self) -> bool:
        """Whether α is known."""
        return self._alpha is not None

    def calibrate(self, matrix: npt.ArrayLike) -> float:
        """Set α = κ(M₀)/δ(M₀) from the initial GIM and return it."""
        if self._alpha is not None:
            raise ConditioningError("the scaled diagonal ratio is already calibrated")
        M = check_gim(matrix)
        self._alpha = condition_number(M) / diagonal_ratio(M)
        return self._alpha

    def __call__(self, matrix_or_diagonal: npt.ArrayLike) -> float:
        """αδ for a GIM or its diagonal; the first full matrix calibrates α if needed."""
        if self._alpha is None:
            if np.ndim(matrix_or_diagonal) != 2:
                raise ConditioningError(
                    "the scaled diagonal ratio needs a full GIM to calibrate α first"
                )
            self.calibrate(matrix_or_diagonal)
        alpha = self._alpha
        assert alpha is not None  # set by calibrate
        return alpha * diagonal_ratio(matrix_or_diagonal)

    def __repr__(self) -> str:
        return f"ScaledDiagonalRatio(alpha={self._alpha!r})"


def ldlt_pivots(matrix: npt.ArrayLike) -> np.ndarray:
    """Pivots of M = L D Lᵀ (L unit lower): Gaussian elimination from the first coordinate.

    No pivoting; ``D_k = L_chol[k, k]²`` from the Cholesky factor.
    """
    M = check_gim(matrix)
    return np.diag(_cholesky_lower(M)) ** 2


def udut_pivots(matrix: npt.ArrayLike) -> np.ndarray:
    """Pivots of M = U D Uᵀ (U unit upper), i.e. elimination from the last coordinate.

    This is the factorisation of Pinocchio's ``cholesky.decompose`` (its ``data.D``) and
    the pivots the O(n) tip-to-root forward-dynamics recursions produce; it equals the
    LDLᵀ of the matrix with its coordinates reversed.
    """
    M = check_gim(matrix)
    return (np.diag(_cholesky_lower(M[::-1, ::-1])) ** 2)[::-1]


def pivot_ratio_forward(matrix: npt.ArrayLike) -> float:
    """max/min of the LDLᵀ pivots (the paper's Gaussian elimination, Fig. 4)."""
    return extreme_ratio(ldlt_pivots(matrix))


def pivot_ratio_backward(matrix: npt.ArrayLike) -> float:
    """max/min of the UDUᵀ pivots (elimination from the tips, as in Pinocchio and DeNOC)."""
    return extreme_ratio(udut_pivots(matrix))


def condition_estimate_1norm(matrix: npt.ArrayLike) -> float:
    """LAPACK ``dpocon``'s estimate of κ₁(M) = ‖M‖₁‖M⁻¹‖₁ from the Cholesky factor.

    The estimate is a lower bound of κ₁ that is usually within a factor of a few; κ₂ lies
    within a factor n of κ₁.
    """
    from scipy.linalg import lapack

    M = check_gim(matrix)
    factor = _cholesky_lower(M)
    anorm = float(np.max(np.sum(np.abs(M), axis=0)))
    rcond, info = lapack.dpocon(factor, anorm, uplo="L")
    if info != 0 or rcond <= 0:
        raise ConditioningError(f"LAPACK dpocon failed (info = {info}, rcond = {rcond})")
    return float(1.0 / rcond)


#: ``IllConditionedWarning`` is issued when κ·eps reaches this value: a solve with M then keeps
#: fewer than two significant digits (relative error bound κ·eps, eps = 2.2e-16 in float64).
ILL_CONDITIONED_KAPPA_EPS = 1e-2


def warn_if_ill_conditioned(kappa: float, *, where: str, stacklevel: int = 2) -> bool:
    """Issue ``IllConditionedWarning`` when κ·eps ≥ `ILL_CONDITIONED_KAPPA_EPS`.

    ``where`` names what M belongs to (robot, configuration) and starts the message.
    Returns True when the warning was issued.
    """
    product = float(kappa) * float(np.finfo(float).eps)
    if not product >= ILL_CONDITIONED_KAPPA_EPS:
        return False
    warnings.warn(
        f"{where}: M is ill-conditioned: kappa = {kappa:.3g}, kappa*eps = {product:.2g} "
        f">= {ILL_CONDITIONED_KAPPA_EPS:g}; results computed with M keep fewer than two "
        "significant digits",
        IllConditionedWarning,
        stacklevel=stacklevel + 1,
    )
    return True
