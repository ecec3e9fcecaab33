"""Atomic writes of results: a file is written to a temporary name, then renamed.

A reader (or an interrupted run) therefore sees either the previous complete file or the
new complete file, never half of one. Only a regular file is ever replaced: a device, a
FIFO or a folder at the target is refused, and a symbolic link is followed (the file it
names is replaced, the link is kept).
"""

from __future__ import annotations

import json
import os
import signal
import stat
import tempfile
import threading
from collections.abc import Iterator, Mapping
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from gimwatch.errors import OutputError

__all__ = [
    "describe_kind",
    "prepare_directory",
    "signals_held",
    "to_json",
    "write_bytes_atomic",
    "write_json_atomic",
    "write_npz_atomic",
    "write_text_atomic",
]


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


_FILE_MODE = 0o666 & ~_umask()


_KINDS = (
    (stat.S_ISDIR, "directory"),
    (stat.S_ISCHR, "character device"),
    (stat.S_ISBLK, "block device"),
    (stat.S_ISFIFO, "FIFO (named pipe)"),
    (stat.S_ISSOCK, "socket"),
    (stat.S_ISLNK, "symbolic link"),
)


def describe_kind(mode: int) -> str:
    """What a file of ``st_mode`` ``mode`` is, in words ("character device", ...)."""
    for test, name in _KINDS:
        if test(mode):
            return name
    return "regular file" if stat.S_ISREG(mode) else "special file"


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM while the block runs; deliver them after it.

    Used where the file system changes state (a rename, a clean-up), so that a signal never
    leaves it half way. In threads other than the main one (which cannot set handlers),
    this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    pending: list[signal.Signals] = []
    previous = {}
    for signum in (signal.SIGINT, signal.SIGTERM):
        try:
            previous[signum] = signal.signal(signum, lambda s, _: pending.append(signal.Signals(s)))
        except (OSError, ValueError):  # pragma: no cover - no handlers here
            pass
    try:
        yield
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, signal.SIG_DFL if handler is None else handler)
        for signum in dict.fromkeys(pending):
            signal.raise_signal(signum)


def _file_target(path: Path) -> Path:
    """The regular file (or free name) ``path`` names, symbolic links followed."""
    if path.is_symlink():
        path = Path(os.path.realpath(path))
    try:
        mode = os.lstat(path).st_mode
    except FileNotFoundError:
        return path
    except OSError as exc:
        raise OutputError(str(path), f"cannot be written ({exc.strerror or exc})") from exc
    if stat.S_ISDIR(mode):
        raise OutputError(str(path), "is a directory; give a file name")
    if not stat.S_ISREG(mode):
        raise OutputError(
            str(path),
            f"is a {describe_kind(mode)}, not a regular file; refusing "
            "to replace it: give a file name",
        )
    return path


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename.

    Raises:
        OutputError: ``path`` is a directory or another file that is not a regular one (a
            device, a FIFO), or its folder cannot be created or written (the previous file,
            if any, is left as it was).
    """
    shown = Path(path)
    path = _file_target(shown)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise OutputError(str(path), f"cannot be written ({exc.strerror or exc})") from exc
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, _FILE_MODE)  # mkstemp makes 0600 files; results are meant to be shared
        with signals_held():
            _file_target(path)  # still a regular file (or nothing) just before the rename
            os.replace(tmp, path)
    except BaseException as exc:
        with signals_held():
            Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise OutputError(str(shown), f"cannot be written ({exc.strerror or exc})") from exc
        raise
    return shown


def prepare_directory(path: str | Path) -> Path:
    """Create the folder ``path`` (and its parents) or raise `OutputError`."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(str(path), "is a file, not a folder; give a folder name")
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(str(path), f"cannot be created ({exc.strerror or exc})") from exc
    return path


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write UTF-8 ``text`` to ``path`` atomically."""
    return write_bytes_atomic(path, text.encode("utf-8"))


def _plain(value: Any) -> Any:
    """Turn NumPy values into Python ones and non-finite floats into None (JSON null)."""
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, np.generic):
        return _plain(value.item())
    if isinstance(value, Path):
        return str(value)
    if isinstance(value, float) and not np.isfinite(value):
        return None
    return value


def to_json(value: Any) -> str:
    """JSON text for records holding NumPy values (non-finite floats become null)."""
    return json.dumps(_plain(value), indent=2, allow_nan=False)


def write_json_atomic(path: str | Path, value: Any) -> Path:
    """Write ``value`` as indented JSON atomically."""
    return write_text_atomic(path, to_json(value) + "\n")


def write_npz_atomic(path: str | Path, arrays: Mapping[str, np.ndarray]) -> Path:
    """Write arrays as an uncompressed ``.npz`` atomically (load with ``allow_pickle=False``)."""
    import io

    buffer = io.BytesIO()
    named: dict[str, Any] = {k: np.asarray(v) for k, v in arrays.items()}
    np.savez(buffer, **named)
    return write_bytes_atomic(path, buffer.getvalue())
