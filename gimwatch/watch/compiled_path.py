"""The watch's compiled sample path: the arithmetic and nothing else, checks folded in.

κ is one scaled eigen-solve by the solver fastest at the watch's size
([`SpectrumSolver`][gimwatch.model.spectrum_solver.SpectrumSolver]; a NaN or non-positive λmin
sends the sample to the checked path, which names the problem: the checks cost nothing on a
good M), δ one compiled call on the diagonal. `CompiledSampling` is a part of
[`Watch`][gimwatch.watch.watch.Watch]: it reads the watch's metric names, robot, Data, MuJoCo
buffer, solver and kernels.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from gimwatch.metrics.registry import GimState
from gimwatch.watch.sources import MujocoSource

__all__ = ["CRBA_DIAGONAL_MAX_NV", "CompiledSampling"]

#: Up to this nv, δ of a ``pinocchio.Model`` without URDF reads CRBA's diagonal (C++, O(n²))
#: rather than the O(n) centroidal map, whose Python around Pinocchio costs more.
CRBA_DIAGONAL_MAX_NV = 40


class CompiledSampling:
    """The compiled path of a watch's sample (a part of `Watch`, not used alone)."""

    def _fast_values(self, source, q) -> list | None:
        """The watched values by the compiled path, or None: then the checked path decides.

        κ: one scaled eigen-solve (the watch's `SpectrumSolver`); a NaN or
        non-positive λmin sends the sample to the checked path, which names the problem, so
        the checks cost nothing on a good M. δ: one compiled call on the diagonal.
        """
        return self._compiled_values(source, q) if self._fast else None

    def _compiled_values(self, source, q) -> list | None:
        if self._only_kappa:
            value = self._solver.ratio(self._gim(source, q))
            return [value] if value >= 1.0 else None  # NaN: the checked path names why
        if self.full:
            M = self._gim(source, q)
            solved = self._solver.scaled(M)
            if solved is None:
                return None
            spectrum, scale = solved
            low = spectrum[0]
            if not low > 0.0:
                return None
            out = []
            for name in self._names:
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
                    out.append(self._kernels.positive_ratio(M.diagonal()))
            return out
        lean = self.lean if source is self.dynamics else source
        if self._names == ("diagonal_ratio",) and lean is not None:
            value = lean.diagonal_ratio(q)
            return [value] if 1.0 <= value < math.inf else None
        diag = self._diagonal(lean, source, q)
        delta = self._kernels.positive_ratio(diag)
        if not delta >= 1.0:
            return None
        return [delta if name == "diagonal_ratio" else diag for name in self._names]

    def _gim(self, source, q) -> np.ndarray:
        if source is None:
            return pin.crba(self.robot.model, self.data, q)
        if isinstance(source, MujocoSource):
            return source.gim(q, out=self._M)
        return source.gim(q)

    def _diagonal(self, lean, source, q) -> np.ndarray:
        if lean is not None:
            return lean.gim_diagonal(q)
        if source is not None:
            return source.gim_diagonal(q)
        if self.nv <= CRBA_DIAGONAL_MAX_NV:  # C++ CRBA beats the O(n) map in Python here
            return pin.crba(self.robot.model, self.data, q).diagonal()
        return GimState(self.robot, self.data, q, False).diag
