"""The process around the command line: signals from start-up to exit, the exit status.

`entry_point` is what ``python -m gimwatch``, ``python -m gimwatch.cli`` and the ``gimwatch``
console script run. SIGINT and SIGTERM are caught from its first line, so that a signal
during start-up (while the command's modules are imported) ends with one line and status
130 or 143 too; a signal after the work is done ends the shutdown without a traceback.
"""

from __future__ import annotations

import os
import signal
import sys

__all__ = ["entry_point"]

_received: list[int] = []


def _interrupt(signum, frame):  # until gimwatch.cli.main installs its latch, and after it
    _received.append(signum)
    raise KeyboardInterrupt


def entry_point() -> None:
    """Run the command line and exit with its status."""
    for signum in (signal.SIGINT, signal.SIGTERM):
        if signal.getsignal(signum) is not signal.SIG_IGN:
            signal.signal(signum, _interrupt)
    try:
        from gimwatch.cli import main  # looked up now, not at import: a test may wrap it

        status = main()
    except KeyboardInterrupt:
        print("gimwatch: interrupted", file=sys.stderr)
        status = 128 + (_received[0] if _received else signal.SIGINT)
    _forget_handled_interrupt()
    try:
        sys.stdout.flush()  # now, not at shutdown, where a closed pipe prints a traceback
    except BrokenPipeError:
        null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(null, sys.stdout.fileno())
        os.close(null)
    for signum in (signal.SIGINT, signal.SIGTERM):  # the work is done: a late signal ends
        if signal.getsignal(signum) is not signal.SIG_IGN:  # the shutdown, without a traceback
            signal.signal(signum, _exit_now)
    sys.exit(status)


def _exit_now(signum, frame):
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(128 + signum)


def _forget_handled_interrupt() -> None:
    """Clear CPython's "KeyboardInterrupt went unhandled" flag: it was handled.

    The flag is set when a KeyboardInterrupt leaves Python code that C code ran (an import
    through a C extension's bindings), even if Python code caught it further up; on exit,
    CPython then kills the process with SIGINT instead of returning the status.
    """
    try:
        import ctypes

        ctypes.c_int.in_dll(ctypes.pythonapi, "_Py_UnhandledKeyboardInterrupt").value = 0
    except (ImportError, AttributeError, ValueError, OSError):  # another Python: nothing to do
        pass
