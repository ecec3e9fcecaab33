"""Alarms of the watch: the record of an upward crossing, its warning, the default threshold.

The watch ([`Watch`][gimwatch.watch.watch.Watch]) compares one watched metric with a
threshold at every sample and acts once per *upward* crossing: it records an
[`Alarm`][gimwatch.watch.alarm.Alarm], calls the user's ``on_alarm(alarm)`` and/or issues
[`IllConditionedWarning`][gimwatch.errors.IllConditionedWarning]
([`warn_alarm`][gimwatch.watch.alarm.warn_alarm]). The default threshold is the one
[`warn_if_ill_conditioned`][gimwatch.metrics.conditioning.warn_if_ill_conditioned] documents: κ·eps
= `ILL_CONDITIONED_KAPPA_EPS`.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from gimwatch.errors import IllConditionedWarning, InputError
from gimwatch.metrics.conditioning import ILL_CONDITIONED_KAPPA_EPS

__all__ = ["DEFAULT_ALARM_THRESHOLD", "Alarm", "alarm_threshold", "check_on_alarm", "warn_alarm"]

#: The alarm threshold when none is given: κ·eps = ILL_CONDITIONED_KAPPA_EPS, κ ≈ 4.5e13.
DEFAULT_ALARM_THRESHOLD = ILL_CONDITIONED_KAPPA_EPS / float(np.finfo(float).eps)


@dataclass(frozen=True)
class Alarm:
    """The alarm metric crossed its threshold at ``time_s`` (upward crossing)."""

    time_s: float
    metric: str
    value: float
    threshold: float

    def message(self) -> str:
        """One line: what crossed what, when (and what the default threshold means)."""
        text = (
            f"watch: {self.metric} = {self.value:.3g} crossed the alarm threshold "
            f"{self.threshold:.3g} at t = {self.time_s:.6g} s"
        )
        if self.threshold == DEFAULT_ALARM_THRESHOLD:
            text += (
                f" (kappa*eps >= {ILL_CONDITIONED_KAPPA_EPS:g}: results computed with M keep "
                "fewer than two significant digits)"
            )
        return text


def alarm_threshold(value: float | None) -> float:
    """The threshold to use: ``value`` checked (finite, > 0), or the default when None."""
    if value is None:
        return DEFAULT_ALARM_THRESHOLD
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating):
        raise InputError("alarm_threshold", "a finite number > 0", value)
    if not 0 < value < math.inf:
        raise InputError("alarm_threshold", "a finite number > 0", value)
    return float(value)


def check_on_alarm(on_alarm: Callable[[Alarm], object] | None) -> None:
    """Refuse an ``on_alarm`` that is neither None nor callable."""
    if on_alarm is not None and not callable(on_alarm):
        kind = type(on_alarm)
        raise InputError(
            "on_alarm", "a callable taking an Alarm", f"{kind.__module__}.{kind.__qualname__}"
        )


def warn_alarm(alarm: Alarm, *, stacklevel: int = 2) -> None:
    """Issue `IllConditionedWarning` with the alarm's message."""
    warnings.warn(alarm.message(), IllConditionedWarning, stacklevel=stacklevel + 1)
