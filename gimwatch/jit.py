"""numba's `njit` for gimwatch's kernels: cached on disk, with a note while compiling.

Every kernel is compiled with ``cache=True``: the first run compiles it (seconds to tens of
seconds for the DeNOC and tracker kernels) and writes the machine code next to the module
(``__pycache__``) or, where the package folder is not writable (a system install), to the
user's cache folder (numba's user-wide locator, ``~/.cache/numba`` on Linux;
``NUMBA_CACHE_DIR`` overrides both). Later processes load it in milliseconds. Where no
folder can be written at all, the kernels are compiled in every process instead of failing.

A compilation (a cache miss, not a cache load) of a gimwatch kernel logs one line on the
``gimwatch`` logger at WARNING level, once per process, so that a slow first run says why it
is slow: on stderr by Python's default (no logging configured), silenced with
``logging.getLogger("gimwatch").setLevel(logging.ERROR)``.
"""

from __future__ import annotations

import logging
from typing import Any

import numba
from numba.core import event

__all__ = ["COMPILE_NOTE", "NOTE", "CompileNote", "njit"]

#: The line printed on stderr when the first gimwatch kernel of a process is compiled.
COMPILE_NOTE = (
    "gimwatch: compiling numba kernels (first run only; cached in {where}, later runs load them)"
)


LOGGER = logging.getLogger("gimwatch")


class CompileNote(event.Listener):
    """Prints `COMPILE_NOTE` on the first compilation of a gimwatch kernel."""

    def __init__(self) -> None:
        self.noted = False

    def on_start(self, ev: event.Event) -> None:
        """Note the first compilation of a kernel defined in a gimwatch module."""
        dispatcher = (ev.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        if self.noted or not module.startswith("gimwatch."):
            return
        self.noted = True
        cache = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
        LOGGER.warning(COMPILE_NOTE.format(where=cache or "numba's cache folder"))

    def on_end(self, ev: event.Event) -> None:
        """Nothing to do when a compilation ends."""


#: The note of this process, registered with numba's event system at import.
NOTE = CompileNote()
event.register("numba:compile", NOTE)


def njit(function: Any = None, **options: Any):
    """``numba.njit`` with ``cache=True`` unless told otherwise (``@njit`` or ``@njit(...)``)."""
    options.setdefault("cache", True)

    def decorate(python_function):
        try:
            dispatcher = numba.njit(**options)(python_function)
        except RuntimeError as exc:  # numba found no folder it may write its cache in
            if "cannot cache" not in str(exc):
                raise
            return numba.njit(**{**options, "cache": False})(python_function)
        _tolerate_cache_write_errors(dispatcher)
        return dispatcher

    return decorate if function is None else decorate(function)


def _tolerate_cache_write_errors(dispatcher) -> None:
    """A cache file that cannot be written (a full disk, a file size limit) is skipped.

    numba writes its cache after compiling, inside the first call of the kernel, and lets an
    OSError from that write escape into the caller: a simulation would then end with a
    traceback for a file that is only an optimisation. The kernel runs uncached instead.
    """
    cache = getattr(dispatcher, "_cache", None)
    save = getattr(cache, "save_overload", None)
    if save is None:
        return

    def save_or_skip(signature, data):
        try:
            save(signature, data)
        except OSError:
            pass

    cache.save_overload = save_or_skip  # type: ignore[union-attr]  # save is not None
