"""The watch's compiled sample path: the arithmetic and nothing else, checks folded in.

κ is one scaled eigen-solve by the solver fastest at the watch's size
([`SpectrumSolver`][gimwatch.watch.spectrum_solver.SpectrumSolver]; a NaN or non-positive λmin
sends the sample to the checked path, which names the problem: the checks cost nothing on a
good M), δ one compiled call on the diagonal (or the source's own δ in one call). A
`CompiledSampler` is built by [`Watch`][gimwatch.watch.watch.Watch] for one source and the
watched metric names; it holds the kernels, the solver and M's buffer.
"""

from __future__ import annotations

import math

import numpy as np

from gimwatch.model.mass_matrix_source import MassMatrixSource

__all__ = ["FAST_METRICS", "CompiledSampler"]

#: Metrics of the compiled sample path: one scaled eigen-solve, or the diagonal alone.
FAST_METRICS = frozenset({"kappa", "eigenvalues", "diagonal_ratio", "diagonal"})


class CompiledSampler:
    """The compiled values of the watched metrics of one source, or None: the checked path.

    Args:
        names: The watched metric names (all in `FAST_METRICS`).
        full: Whether a watched metric needs M itself (then one eigen-solve serves all).
        source: Where M(q) comes from; its ``gim_into``, ``gim_diagonal`` and
            ``diagonal_ratio`` are bound once.
    """

    def __init__(self, names: tuple[str, ...], full: bool, source: MassMatrixSource) -> None:
        from gimwatch.watch import kernels  # numba: imported when a watch is built, not before
        from gimwatch.watch.spectrum_solver import SpectrumSolver

        self.names, self.full, self.kernels = names, full, kernels
        self.only_kappa = names == ("kappa",)
        self.only_ratio = names == ("diagonal_ratio",)
        self.solver = SpectrumSolver(source.nv) if full else None
        self.buffer = np.empty((source.nv, source.nv)) if full else np.empty((0, 0))
        self.gim_into = source.gim_into
        self.gim_diagonal = source.gim_diagonal
        self.diagonal_ratio = source.diagonal_ratio

    def values(self, q: np.ndarray | None) -> list | None:
        """The watched values at q by the compiled path, or None: the checked path decides.

        κ: one scaled eigen-solve; a NaN or non-positive λmin sends the sample to the checked
        path, which names the problem, so the checks cost nothing on a good M. δ: one compiled
        call on the diagonal.
        """
        if self.full:
            M = self.gim_into(q, self.buffer)
            if self.only_kappa:
                value = self.solver.ratio(M)  # type: ignore[union-attr]
                return [value] if value >= 1.0 else None  # NaN: the checked path names why
            return self._spectrum_values(M)
        if self.only_ratio:
            ratio = self.diagonal_ratio(q)
            if ratio is not None:
                return [ratio] if 1.0 <= ratio < math.inf else None
        diag = self.gim_diagonal(q)
        delta = self.kernels.positive_ratio(diag)
        if not delta >= 1.0:
            return None
        return [delta if name == "diagonal_ratio" else diag for name in self.names]

    def _spectrum_values(self, M: np.ndarray) -> list | None:
        solved = self.solver.scaled(M)  # type: ignore[union-attr]
        if solved is None:
            return None
        spectrum, scale = solved
        low = spectrum[0]
        if not low > 0.0:
            return None
        out = []
        for name in self.names:
            # A λmin near the smallest float gives κ = inf (and λ·scale may overflow): that
            # is the value watched (the alarm fires on it), not a fault to warn about.
            if name == "kappa":
                with np.errstate(over="ignore"):
                    out.append(spectrum[-1] / low)
            elif name == "eigenvalues":
                with np.errstate(over="ignore"):
                    out.append(spectrum * scale)
            elif name == "diagonal":
                out.append(M.diagonal())
            else:
                out.append(self.kernels.positive_ratio(M.diagonal()))
        return out
