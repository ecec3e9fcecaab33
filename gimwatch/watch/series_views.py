"""What a watch hands out of its series: arrays, a DataFrame, a figure.

A `SeriesViews` is held by a [`Watch`][gimwatch.watch.watch.Watch], which delegates to it: it
reads the recorded series and the watched metrics it was given; nothing is computed here.
"""

from __future__ import annotations

import numpy as np
import numpy.typing as npt

from gimwatch.errors import InputError
from gimwatch.metrics.registry import Metric
from gimwatch.watch.series import WatchSeries

__all__ = ["SeriesViews"]


class SeriesViews:
    """The outputs of a watch's series.

    Args:
        series: The recorded samples.
        metrics: The watched metrics by name (their records and severities are read here).
    """

    def __init__(self, series: WatchSeries, metrics: dict[str, Metric]) -> None:
        self._series, self.metrics = series, metrics

    @property
    def times(self) -> np.ndarray:
        """The sample times (s) so far (a read-only view)."""
        return self._series.times

    @property
    def series(self) -> dict[str, np.ndarray]:
        """Name -> the watched metric's values so far (read-only views; vector metrics 2-D)."""
        return self._series.columns()

    def array(self, name: str) -> np.ndarray:
        """One series as an array: ``"t"`` (s) or a watched metric (vector metrics: 2-D)."""
        if name == "t":
            return self.times.copy()
        if name not in self.metrics:
            watched = list(self.metrics)
            raise InputError("the series name", f"'t' or a watched metric {watched}", name)
        return self.series[name].copy()

    def arrays(self) -> dict[str, np.ndarray]:
        """The series as arrays, keyed ``watch_<metric>`` plus ``watch_t``."""
        out = {"watch_t": self.times.copy()}
        for name, values in self.series.items():
            out[f"watch_{name}"] = values.copy()
        samples = len(out["watch_t"])
        for name, metric in self.metrics.items():  # what a metric records besides its value
            for suffix, record in metric.records(samples).items():
                out[f"watch_{name}_{suffix}"] = record
        return out

    def to_dataframe(self):
        """The series as a pandas DataFrame: ``t`` and one column per scalar metric.

        Vector metrics (``eigenvalues``, ``diagonal``) are spread into ``<metric>:<k>``.
        Needs pandas (``pip install 'gimwatch[pandas]'``).
        """
        from gimwatch.output.dataframe import watch_frame

        return watch_frame(self.arrays())

    def plot(
        self,
        metrics: tuple[str, ...] | None = None,
        *,
        ax=None,
        alarm: tuple[str | None, float] = (None, 0.0),
    ):
        """The watched scalar metrics over time on a log axis, with the alarm threshold.

        For the own-loop case, the figure a results folder has for ``simulate``
        (`gimwatch.output.figures.plot_watch`). Vector metrics (eigenvalues, diagonal)
        are left out.

        Args:
            metrics: Which watched metrics (default: every scalar one).
            ax: Matplotlib Axes to draw on (a new figure's when None).
            alarm: The watch's alarm metric (None for none) and threshold.

        Returns:
            The Axes.
        """
        from gimwatch.output.figures import plot_watch

        scalar = [name for name, metric in self.metrics.items() if not metric.vector]
        chosen = scalar if metrics is None else list(metrics)
        unknown = [n for n in chosen if n not in scalar]
        if unknown or not chosen:
            raise InputError("the metrics to plot", f"watched scalar metrics {scalar}", unknown)
        alarm_metric, alarm_threshold = alarm
        threshold = None
        if alarm_metric in chosen:  # drawn where the metric's value is its severity
            severity = self.metrics[alarm_metric].severity
            if severity(alarm_threshold) == alarm_threshold:
                threshold = alarm_threshold
        series: dict[str, npt.ArrayLike] = {name: self.array(name) for name in chosen}
        return plot_watch(
            self.array("t"), series, alarm_metric=alarm_metric, threshold=threshold, ax=ax
        )
