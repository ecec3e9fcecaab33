"""A reader that stops early (``gimwatch analyze ur5 --json | head -c 100``) ends no command.

When the reader of stdout closes the pipe, the rest of the output is thrown away: stdout is
pointed at the null device (so neither later writes nor the interpreter's last flush raise
``BrokenPipeError``), and the command goes on to its own exit status. Exit status 1 means "a
check failed", so a closed pipe must not turn into it.
"""

from __future__ import annotations

import os
import sys
from typing import TextIO


class QuietPipe:
    """``sys.stdout`` whose writes end quietly once the reader has closed the pipe."""

    def __init__(self, stream: TextIO) -> None:
        self._stream = stream
        self.closed_by_reader = False

    def write(self, text: str) -> int:
        if not self.closed_by_reader:
            try:
                return self._stream.write(text)
            except BrokenPipeError:
                self.discard()
        return len(text)

    def flush(self) -> None:
        if not self.closed_by_reader:
            try:
                self._stream.flush()
            except BrokenPipeError:
                self.discard()

    def discard(self) -> None:
        """Send the rest of the output (and what is still buffered) to the null device."""
        self.closed_by_reader = True
        discard_stdout(self._stream)

    def __getattr__(self, name: str):
        return getattr(self._stream, name)


def discard_stdout(stream: TextIO | None = None) -> None:
    """Point the file descriptor of ``stream`` (stdout) at the null device."""
    stream = sys.__stdout__ if stream is None else stream
    if stream is None:  # no stdout at all (pythonw): nothing to do
        return
    try:
        descriptor = stream.fileno()
    except (AttributeError, OSError, ValueError):  # not a file (a test's capture): nothing to do
        return
    null = os.open(os.devnull, os.O_WRONLY)
    try:
        os.dup2(null, descriptor)
    finally:
        os.close(null)
