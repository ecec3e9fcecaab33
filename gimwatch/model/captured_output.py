"""What C and C++ code (urdfdom, Pinocchio's parsers, MuJoCo's compiler) prints, captured.

Third-party libraries write to file descriptors 1 and 2 directly, past Python's streams;
gimwatch keeps stderr for its own one-line messages, so their output is captured here and
either re-worded into a gimwatch error or dropped.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from collections.abc import Iterator

__all__ = ["captured_c_output"]


@contextlib.contextmanager
def captured_c_output(fd: int = 2) -> Iterator[list[str]]:
    """Capture what C/C++ code (urdfdom, MuJoCo's compiler) writes to file descriptor ``fd``.

    Yields a list that holds the captured lines once the block has ended.
    """
    lines: list[str] = []
    stream = sys.stdout if fd == 1 else sys.stderr
    try:
        stream.flush()
        saved = os.dup(fd)
    except (OSError, ValueError, AttributeError):  # no such stream to protect
        yield lines
        return
    with tempfile.TemporaryFile() as sink:
        os.dup2(sink.fileno(), fd)
        try:
            yield lines
        finally:
            os.dup2(saved, fd)
            os.close(saved)
            sink.seek(0)
            text = sink.read().decode("utf-8", "replace")
            lines.extend(line.strip() for line in text.splitlines() if line.strip())
