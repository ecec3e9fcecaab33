"""The one progress bar of the command line: tqdm on stderr, for runs longer than 2 s.

Every long command shows its progress through tqdm (a dependency): ``simulate`` and
``demo`` through `ProgressBar` (a fraction done), ``survey`` through tqdm directly (chunks).
The bar is drawn on a terminal only (``disable=None``): logs and pipes get no carriage
returns.
"""

from __future__ import annotations

import sys

from tqdm import tqdm


class ProgressBar:
    """Called with the fraction done; draws after ``delay_s``, at most ``rate_hz`` per second."""

    def __init__(self, label: str, *, delay_s: float = 2.0, rate_hz: float = 5.0, stream=None):
        self.bar = tqdm(
            total=1.0,
            desc=label,
            file=sys.stderr if stream is None else stream,
            delay=delay_s,
            mininterval=1.0 / rate_hz,
            leave=False,
            disable=None,  # a terminal only
            bar_format="{desc} {bar} {percentage:5.1f}% {elapsed}",
        )

    def __call__(self, fraction: float) -> None:
        if self.bar.disable:
            return
        self.bar.update(min(max(fraction, 0.0), 1.0) - self.bar.n)

    def close(self) -> None:
        """Remove the bar."""
        self.bar.close()
