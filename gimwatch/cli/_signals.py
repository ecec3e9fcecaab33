"""SIGINT and SIGTERM in the command line: a latch, and exit statuses 130 and 143.

While `LATCH` is installed (for the length of `gimwatch.cli.main`), SIGINT
(Ctrl-C) and SIGTERM raise `KeyboardInterrupt` where Python code runs, so every
command stops as on Ctrl-C and keeps what it computed. Inside `SignalLatch.deferred`
a signal is only noted:

* ``"hard"`` (compiled code runs: numba's DeNOC recursions and their compilation, where an
  exception raised from a signal handler ends in a ``SystemError``): every signal is noted
  and `SignalLatch.check` raises at the next safe point, between integrator steps
  (a third signal raises at once: the user insists);
* ``"soft"`` (a results folder is being written): the first signal is noted and the write
  completes; a second one raises, and the folder is left as it was.

The exit status says which signal came first: 130 for SIGINT, 143 for SIGTERM (128 + N).
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from types import FrameType

__all__ = ["LATCH", "SignalLatch", "exit_status"]

_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: The signal that raises even while deferred: the user insists (a stuck load, a long step).
_INSIST = 3
#: What `signal.getsignal` returns and `signal.signal` accepts.
_Handler = Callable[[int, FrameType | None], object] | int | signal.Handlers | None


def exit_status(signum: int | None) -> int:
    """128 + the signal's number: 130 for SIGINT (and a plain Ctrl-C), 143 for SIGTERM."""
    return 128 + int(signum if signum is not None else signal.SIGINT)


class SignalLatch:
    """Turns SIGINT and SIGTERM into `KeyboardInterrupt`, or notes them while deferred.

    Attributes:
        signum: The first signal received since `install`, or None.
        pending: A noted signal has not raised yet.
    """

    def __init__(self) -> None:
        self.signum: int | None = None
        self.pending = False
        self._mode: str | None = None
        self._count = 0
        self._previous: dict[int, _Handler] = {}

    def install(self) -> bool:
        """Install the handlers (main thread only); False when they could not be installed.

        A signal the process ignores (SIGINT in a background job) stays ignored.
        """
        self.signum, self.pending, self._mode, self._count = None, False, None, 0
        if threading.current_thread() is not threading.main_thread() or self._previous:
            return False
        for signum in _SIGNALS:
            current = signal.getsignal(signum)
            if current is signal.SIG_IGN:
                continue
            self._previous[signum] = current
            signal.signal(signum, self._handle)
        return True

    def uninstall(self) -> None:
        """Put back the handlers found by `install`."""
        for signum, handler in self._previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        self._previous.clear()

    def _handle(self, signum: int, frame: object) -> None:
        if self.signum is None:
            self.signum = signum
        self._count += 1
        insisted = self._count >= _INSIST
        if not insisted and (self._mode == "hard" or (self._mode == "soft" and not self.pending)):
            self.pending = True
            return
        self.pending = False
        raise KeyboardInterrupt

    @contextmanager
    def deferred(self, mode: str = "soft") -> Iterator[None]:
        """Note signals instead of raising while the block runs (``"soft"`` or ``"hard"``)."""
        previous, self._mode = self._mode, mode
        try:
            yield
        finally:
            self._mode = previous

    def check(self) -> None:
        """Raise `KeyboardInterrupt` if a noted signal has not raised yet."""
        if self.pending:
            self.pending = False
            raise KeyboardInterrupt

    def checking(self, progress: Callable[[float], object]) -> Callable[[float], object]:
        """``progress`` preceded by `check`: a safe point between integrator steps."""

        def checked(fraction: float) -> object:
            self.check()
            return progress(fraction)

        return checked

    @property
    def exit_status(self) -> int:
        """130 (SIGINT) or 143 (SIGTERM): the status for the first signal received."""
        return exit_status(self.signum)


#: The command line's latch.
LATCH = SignalLatch()
