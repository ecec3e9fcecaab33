"""The command line stopped at one phase, for the fault tests: ``fault_pause.py PHASE ARGS``.

The production code has no test hook: this launcher wraps the function the command calls at
the chosen moment, then runs ``python -m gimwatch ARGS`` in this process. At the phase it
prints ``gimwatch: paused at PHASE`` on stderr, waits (at most ten minutes) for SIGINT or
SIGTERM, then delivers the signal to the handler in place, as if it had arrived there:

* ``startup``: the start-up signal handlers are installed, the command line not yet run;
* ``import``: inside the command line, before the command's modules are imported;
* ``compute``: after the first integrator step (simulate) or chunk (survey);
* ``write``: the results are in the staging folder, not yet in place;
* ``swap``: the new folder is in place, the previous one not yet deleted.
"""

from __future__ import annotations

import runpy
import signal
import sys
import threading
import time

_SIGNALS = (signal.SIGINT, signal.SIGTERM)
_paused: set[str] = set()


def pause(phase: str) -> None:
    """Stop here (once, in the main thread) until a signal arrives; then deliver it."""
    if phase in _paused or threading.current_thread() is not threading.main_thread():
        return
    _paused.add(phase)
    received: list[int] = []
    previous = {s: signal.signal(s, lambda n, _: received.append(n)) for s in _SIGNALS}
    try:
        print(f"gimwatch: paused at {phase}", file=sys.stderr, flush=True)
        deadline = time.monotonic() + 600.0
        while not received and time.monotonic() < deadline:
            time.sleep(0.005)
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        for signum in received:
            signal.raise_signal(signum)


def _before(owner, name: str, phase: str) -> None:
    """Make ``owner.name`` pause at ``phase`` before it runs."""
    original = getattr(owner, name)

    def paused(*args, **kwargs):
        pause(phase)
        return original(*args, **kwargs)

    setattr(owner, name, paused)


def _after(owner, name: str, phase: str) -> None:
    """Make ``owner.name`` pause at ``phase`` after it returns."""
    original = getattr(owner, name)

    def paused(*args, **kwargs):
        result = original(*args, **kwargs)
        pause(phase)
        return result

    setattr(owner, name, paused)


def install(phase: str) -> None:
    """Wrap what the command calls at ``phase``."""
    import gimwatch.cli

    if phase == "startup":  # gimwatch.cli.startup.entry_point looks main up when it runs
        _before(gimwatch.cli, "main", phase)
    elif phase == "import":  # the first call inside main's deferred block, before any import
        _before(gimwatch.cli, "get_argument_parser", phase)
    elif phase == "compute":  # the progress callbacks of simulate and survey
        import tqdm

        import gimwatch.cli._progress
        import gimwatch.cli.simulate

        _before(gimwatch.cli._progress.ProgressBar, "__call__", phase)
        _before(tqdm.tqdm, "update", phase)
    elif phase == "write":
        from gimwatch.output.folders import ResultsFolder

        _before(ResultsFolder, "commit", phase)
    elif phase == "swap":
        from gimwatch.output import folders

        _after(folders, "swap", phase)
    else:
        raise SystemExit(f"fault_pause.py: unknown phase {phase!r}")


if __name__ == "__main__":
    install(sys.argv[1])
    sys.argv = ["gimwatch", *sys.argv[2:]]
    runpy.run_module("gimwatch", run_name="__main__", alter_sys=True)
