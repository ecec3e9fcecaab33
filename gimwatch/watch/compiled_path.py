"""The watch's compiled sample path: the arithmetic and nothing else, checks folded in.

κ is one scaled eigen-solve (a NaN or non-positive λmin sends the sample to the checked path,
which names the problem: the checks cost nothing on a good M), δ one compiled call on the
diagonal. `CompiledSampling` is a part of [`Watch`][gimwatch.watch.watch.Watch]: it
reads the watch's metric names, robot, Data, MuJoCo buffer and kernels.
"""

from __future__ import annotations

import math

import numpy as np
import pinocchio as pin

from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.registry import GimState
from gimwatch.watch.sources import MujocoSource

__all__ = ["CRBA_DIAGONAL_MAX_NV", "NUMPY_EIG_MIN_NV", "CompiledSampling"]

#: Above this nv a κ-only watch solves with NumPy's ``eigvalsh`` (after the compiled scale
#: check): its LAPACK build beats the one numba calls there, and its wrapper's µs no longer count.
NUMPY_EIG_MIN_NV = 24

#: Up to this nv, δ of a ``pinocchio.Model`` without URDF reads CRBA's diagonal (C++, O(n²))
#: rather than the O(n) centroidal map, whose Python around Pinocchio costs more.
CRBA_DIAGONAL_MAX_NV = 40


class CompiledSampling:
    """The compiled path of a watch's sample (a part of `Watch`, not used alone)."""

    def _fast_values(self, source, q) -> list | None:
        """The watched values by the compiled path, or None: then the checked path decides.

        κ: one scaled eigen-solve (`scaled_spectrum`); a NaN or
        non-positive λmin sends the sample to the checked path, which names the problem, so
        the checks cost nothing on a good M. δ: one compiled call on the diagonal.
        """
        if not self._fast:
            return None
        try:
            return self._compiled_values(source, q)
        except np.linalg.LinAlgError:  # NaN in M reached LAPACK: the checked path says where
            return None

    def _compiled_values(self, source, q) -> list | None:
        if self._only_kappa and self.nv > NUMPY_EIG_MIN_NV:  # NumPy's LAPACK is faster there
            M = self._gim(source, q)
            scale = self._kernels.spectrum_scale(M)
            if not scale > 0.0:
                return None
            values = np.linalg.eigvalsh(M if scale == 1.0 else M * (1.0 / scale))
            value = extreme_ratio(values)
            return [value] if value >= 1.0 else None
        if self._only_kappa:
            value = self._kernels.spectrum_ratio(self._gim(source, q))
            return [value] if value >= 1.0 else None  # NaN: the checked path names why
        if self.full:
            M = self._gim(source, q)
            spectrum, scale = self._kernels.scaled_spectrum(M)
            low = spectrum[0]
            if not low > 0.0:
                return None
            out = []
            for name in self._names:
                if name == "kappa":
                    out.append(spectrum[-1] / low)
                elif name == "eigenvalues":
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
