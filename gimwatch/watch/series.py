"""The watch's series: sample times and one growing NumPy array per named quantity.

A sample writes one row into preallocated arrays (capacity doubled when full), never a
Python list per sample. Each named series is a scalar column or, for vector metrics
(``eigenvalues``, ``diagonal``), a 2-D array (samples × nv). New named series (a per-sample
fallback flag, an error bound) are one more entry of the dict: `add`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["WatchSeries"]

#: Rows allocated at first; doubled whenever full.
INITIAL_CAPACITY = 256


class WatchSeries:
    """Sample times (s) and named series, stored in arrays that grow by doubling.

    Args:
        widths: name -> 0 for a scalar series, k for a vector series of k entries.
    """

    def __init__(self, widths: dict[str, int]) -> None:
        self.size = 0
        self._capacity = INITIAL_CAPACITY
        self._t = np.empty(self._capacity)
        self._data: dict[str, np.ndarray] = {}
        for name, width in widths.items():
            self.add(name, width)

    def add(self, name: str, width: int = 0) -> None:
        """A new named series (NaN for the samples already recorded)."""
        shape = (self._capacity,) if width == 0 else (self._capacity, width)
        self._data[name] = np.full(shape, np.nan)

    def append(self, t: float, values) -> None:
        """Record one sample: time ``t`` and one value per series, in the order of ``add``."""
        k = self.size
        if k == self._capacity:
            self._grow()
        self._t[k] = t
        for column, value in zip(self._data.values(), values, strict=True):
            column[k] = value
        self.size = k + 1

    def _grow(self) -> None:
        self._capacity *= 2
        self._t = np.resize(self._t, self._capacity)
        for name, column in self._data.items():
            bigger = np.full((self._capacity, *column.shape[1:]), np.nan)
            bigger[: self.size] = column[: self.size]
            self._data[name] = bigger

    @property
    def times(self) -> np.ndarray:
        """The sample times (s), a read-only view."""
        return _view(self._t[: self.size])

    def columns(self) -> dict[str, np.ndarray]:
        """Name -> its values so far (read-only views; copy to keep them past new samples)."""
        return {name: _view(column[: self.size]) for name, column in self._data.items()}

    def last(self, name: str):
        """The latest value of one series."""
        return self._data[name][self.size - 1]


def _view(array: np.ndarray) -> np.ndarray:
    view = array.view()
    view.flags.writeable = False
    return view
