"""numba's `njit` for gimwatch's kernels: cached on disk, with a note while compiling.

Every kernel is compiled with ``cache=True``: the first run compiles it (seconds to tens of
seconds for the DeNOC and tracker kernels) and writes the machine code next to the module
(``__pycache__``) or, where the package folder is not writable (a system install), to the
user's cache folder (numba's user-wide locator, ``~/.cache/numba`` on Linux;
``NUMBA_CACHE_DIR`` overrides both). Later processes load it in milliseconds. Where no
folder can be written at all, the kernels are compiled in every process instead of failing.

A compilation (a cache miss, not a cache load) of a gimwatch kernel logs one line on the
``gimwatch`` logger at WARNING level, once per install (a marker file next to the cache
records that it was said), so that a slow first run says why it is slow and what the next
first runs cost: on stderr by Python's default (no logging configured), silenced with
``logging.getLogger("gimwatch").setLevel(logging.ERROR)``. Each kind of work compiles its own
kernels on its first run (a watch with δ, a crosscheck, an O(n) chain); they say nothing more.
"""

from __future__ import annotations

import logging
import os
from pathlib import Path
from typing import Any

import numba
from numba.core import event

__all__ = ["COMPILE_NOTE", "NOTE", "CompileNote", "install_marker", "njit"]

#: The line printed on stderr when the first gimwatch kernel of an install is compiled.
COMPILE_NOTE = (
    "gimwatch: compiling numba kernels, once per install: the first watch with delta, "
    "crosscheck or O(n) chain run takes 10-40 s longer (cached in {where}; later runs load them)"
)


LOGGER = logging.getLogger("gimwatch")


def install_marker() -> Path:
    """The file whose presence says this install's note was given.

    In the folder numba caches gimwatch's kernels in: ``$NUMBA_CACHE_DIR``, else the package's
    ``__pycache__`` when writable, else numba's user-wide folder (``~/.cache/numba``).
    """
    from gimwatch._version import __version__

    name = f"gimwatch-{__version__}-compile-noted"
    if os.environ.get("NUMBA_CACHE_DIR"):
        return Path(os.environ["NUMBA_CACHE_DIR"]) / name
    package_cache = Path(__file__).parent / "__pycache__"
    if os.access(package_cache if package_cache.exists() else package_cache.parent, os.W_OK):
        return package_cache / name
    return Path.home() / ".cache" / "numba" / name


class CompileNote(event.Listener):
    """Prints `COMPILE_NOTE` on the first compilation of a gimwatch kernel of an install.

    Args:
        marker: The file that records the note was given (`install_marker`); ``None`` notes
            once per process.
    """

    def __init__(self, marker: Path | None = None) -> None:
        self.noted = False
        self.marker = marker

    def on_start(self, ev: event.Event) -> None:
        """Note the first compilation of a kernel defined in a gimwatch module."""
        dispatcher = (ev.data or {}).get("dispatcher")
        module = getattr(getattr(dispatcher, "py_func", None), "__module__", "") or ""
        if self.noted or not module.startswith("gimwatch."):
            return
        self.noted = True
        if self.marker is not None and self.marker.exists():
            return  # said by an earlier process of this install
        cache = getattr(getattr(dispatcher, "_cache", None), "_cache_path", None)
        LOGGER.warning(COMPILE_NOTE.format(where=cache or "numba's cache folder"))
        if self.marker is not None:
            try:
                self.marker.parent.mkdir(parents=True, exist_ok=True)
                self.marker.touch()
            except OSError:  # a read-only install: the note comes again, nothing fails
                pass

    def on_end(self, ev: event.Event) -> None:
        """Nothing to do when a compilation ends."""


#: The note of this process, registered with numba's event system at import.
NOTE = CompileNote(install_marker())
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
