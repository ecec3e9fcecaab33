"""The command line's one progress bar (tqdm): drawn on a terminal after its delay only."""

from __future__ import annotations

import io
import time

from gimwatch.cli._progress import ProgressBar


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_the_bar_draws_on_a_terminal_after_its_delay():
    stream = Terminal()
    bar = ProgressBar("chain_4", delay_s=0.0, rate_hz=1e6, stream=stream)
    for fraction in (0.25, 0.5, 1.0):
        time.sleep(0.001)
        bar(fraction)
    bar.close()
    text = stream.getvalue()
    assert "chain_4" in text and "100.0%" in text and " 50.0%" in text


def test_nothing_is_drawn_before_the_delay_or_into_a_pipe():
    quick, pipe = Terminal(), io.StringIO()
    for stream in (quick, pipe):
        bar = ProgressBar("run", delay_s=60.0 if stream is quick else 0.0, stream=stream)
        bar(0.5)
        bar(1.0)
        bar.close()
    assert "run" not in quick.getvalue() and pipe.getvalue() == ""
