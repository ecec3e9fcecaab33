"""``python -m gimwatch`` and the ``gimwatch`` console script.

SIGINT and SIGTERM are caught from the first line, so that a signal during start-up (while
the command line's modules are imported) ends with one line and status 130 or 143 too.
"""

import os
import signal
import sys
import time

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
        if os.environ.get("GIMWATCH_FAULT_PAUSE") == "startup":  # fault tests signal here
            print("gimwatch: paused at startup", file=sys.stderr, flush=True)
            time.sleep(60.0)
        from gimwatch.cli import main

        status = main()
    except KeyboardInterrupt:
        print("gimwatch: interrupted", file=sys.stderr)
        status = 128 + (_received[0] if _received else signal.SIGINT)
    sys.exit(status)


if __name__ == "__main__":
    entry_point()
