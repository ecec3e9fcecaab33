"""A progress bar on stderr that appears only for runs longer than a couple of seconds."""

from __future__ import annotations

import sys
import time


class ProgressBar:
    """Called with the fraction done; draws after ``delay_s``, at most ``rate_hz`` per second."""

    def __init__(self, label: str, *, delay_s: float = 2.0, rate_hz: float = 5.0, stream=None):
        self.label, self.delay_s, self.period = label, delay_s, 1.0 / rate_hz
        self.stream = sys.stderr if stream is None else stream
        self.start = time.monotonic()
        self.last = -1.0
        self.drawn = False

    def __call__(self, fraction: float) -> None:
        now = time.monotonic()
        if now - self.start < self.delay_s or now - self.last < self.period:
            return
        self.last = now
        width = 30
        filled = round(width * min(max(fraction, 0.0), 1.0))
        bar = "#" * filled + "." * (width - filled)
        elapsed = now - self.start
        self.stream.write(f"\r{self.label} [{bar}] {100 * fraction:5.1f}% {elapsed:6.1f} s")
        self.stream.flush()
        self.drawn = True

    def close(self) -> None:
        """End the bar's line if one was drawn."""
        if self.drawn:
            self.stream.write("\n")
            self.stream.flush()
