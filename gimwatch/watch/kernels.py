"""Compiled per-sample arithmetic: the spectrum of M, δ, and the check of q's unit blocks.

Small numba kernels (cached on disk, so only the first run ever compiles them) that the
watch calls once per sample instead of several NumPy reductions around a LAPACK call:

* `scaled_spectrum` — the eigenvalues of M / s, s a power of two near max M_ii,
  ascending (LAPACK's symmetric solver, called from compiled code without NumPy's wrapper).
  Scaling first keeps a finite M finite: ``[[2, 1], [1, 2]] · 8e307`` has κ = 3, not inf.
  κ = λmax / λmin needs no rescaling (Shah & Saha 2013, Eq. 6). A bad M gives a NaN or
  non-positive spectrum (or LinAlgError): the caller's checked path then names the
  problem, so the check costs nothing when M is good.
* `spectrum_scale` — that s, from the diagonal alone.
* `spectrum_ratio` — κ alone from that spectrum, NaN when M is not finite and > 0.
* `positive_ratio` — max / min of a vector (δ, Sec. 4), NaN unless every entry is
  finite and > 0.
* `unit_block_fault` — the first unit block of q (a quaternion, a continuous joint's
  (cos θ, sin θ)) whose norm is not 1, or a non-finite entry, in one pass without a Python
  loop over joints.
"""

from __future__ import annotations

import math

import numpy as np

from gimwatch.jit import njit

__all__ = [
    "positive_ratio",
    "scaled_spectrum",
    "spectrum_ratio",
    "spectrum_scale",
    "unit_block_fault",
]

_FINITE_MAX = np.finfo(np.float64).max
#: Entries of M between these need no scaling: the solve keeps clear of overflow and of
#: subnormal numbers (M is then solved as given, s = 1).
SAFE_LOW, SAFE_HIGH = 2.0**-400, 2.0**400


@njit
def spectrum_scale(M):  # pragma: no cover - compiled
    """The s of `scaled_spectrum` from diag M (n reads, not n²); NaN if it is not > 0.

    For a positive definite M, |M_ij| <= sqrt(M_ii M_jj) <= max M_ii, so the diagonal bounds
    every entry. An M that is not (huge off-diagonal entries, NaN off the diagonal) gives
    a non-positive, non-finite spectrum or LAPACK's LinAlgError: the caller's checked path.
    s = 1 when max M_ii lies in [SAFE_LOW, SAFE_HIGH], where scaling changes nothing.
    """
    scale = 0.0
    for i in range(M.shape[0]):
        a = M[i, i]
        if not 0.0 < a <= _FINITE_MAX:
            return np.nan
        if a > scale:
            scale = a
    if SAFE_LOW <= scale <= SAFE_HIGH:
        return 1.0
    return math.ldexp(1.0, math.frexp(scale)[1] - 1)  # 2^k <= scale: rounds nothing


@njit
def scaled_spectrum(M):  # pragma: no cover - compiled
    """(eigenvalues of M / s ascending, s), s = 2^k <= max M_ii < 2^(k+1) (`spectrum_scale`).

    M is read, not written (symmetric, lower triangle used). A diagonal entry <= 0 or not
    finite gives a NaN spectrum; NaN off the diagonal raises LAPACK's LinAlgError.
    """
    scale = spectrum_scale(M)
    if not scale > 0.0:
        return np.full(M.shape[0], np.nan), np.nan
    if scale == 1.0:  # no overflow or underflow ahead: skip the copy
        return np.linalg.eigvalsh(M), 1.0
    return np.linalg.eigvalsh(M * (1.0 / scale)), scale


@njit
def spectrum_ratio(M):  # pragma: no cover - compiled
    """κ = λmax / λmin of M (Eq. 6) by `scaled_spectrum`; NaN unless M is finite and > 0."""
    spectrum, _ = scaled_spectrum(M)
    low = spectrum[0]
    if not low > 0.0:
        return np.nan
    return spectrum[-1] / low


@njit
def positive_ratio(values):  # pragma: no cover - compiled
    """Max / min of ``values``; NaN unless all are finite and > 0."""
    lo = np.inf
    hi = 0.0
    for x in values:
        if not 0.0 < x <= _FINITE_MAX:
            return np.nan
        lo = min(lo, x)
        hi = max(hi, x)
    return hi / lo


@njit
def unit_block_fault(q, stops, sizes, tolerance):  # pragma: no cover - compiled
    """-1 when q is finite and every unit block has norm 1 within ``tolerance``.

    Else -2 for a non-finite entry, or k >= 0 for the first bad block (its block ends at
    ``stops[k]`` and has ``sizes[k]`` entries).
    """
    for x in q:
        if not abs(x) <= _FINITE_MAX:
            return -2
    for k in range(stops.shape[0]):
        total = 0.0
        for i in range(stops[k] - sizes[k], stops[k]):
            total += q[i] * q[i]
        if not abs(np.sqrt(total) - 1.0) <= tolerance:
            return k
    return -1
