"""The one progress bar of the command line: tqdm on stderr, for runs longer than 2 s.

Every long command shows its progress through tqdm (a dependency): ``simulate`` and
``demo`` through `ProgressBar` (a fraction done), ``survey`` through tqdm directly (chunks).
The bar is drawn on a terminal only (``disable=None``): logs and pipes get no carriage
returns.
"""

from __future__ import annotations

import sys


class ProgressBar:
    """Called with the fraction done; draws after ``delay_s``, at most ``rate_hz`` per second."""

    def __init__(self, label: str, *, delay_s: float = 2.0, rate_hz: float = 5.0, stream=None):
        from tqdm import tqdm  # here, not at import: a short command should not pay for it

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


class ItemProgress:
    """Progress over a list of named items (robots of a batch).

    On a terminal, one tqdm bar naming the current item; in a log or a pipe, one line per
    item (``label: [i/n] item``), which a log keeps and a bar's carriage returns would garble.
    """

    def __init__(self, label: str, total: int, *, stream=None) -> None:
        self.label, self.total, self.index = label, total, 0
        self.stream = sys.stderr if stream is None else stream
        from tqdm import tqdm

        self.bar = tqdm(
            total=total, desc=label, file=self.stream, leave=False, disable=None, unit="robot"
        )

    def start(self, item: str) -> None:
        """The next item begins."""
        self.index += 1
        if self.bar.disable:
            print(f"{self.label}: [{self.index}/{self.total}] {item}", file=self.stream)
        else:
            if self.index > 1:
                self.bar.update(1)
            self.bar.set_postfix_str(item)

    def close(self) -> None:
        """Remove the bar."""
        self.bar.close()
