"""Atomic writes of results: a file is written to a temporary name, then renamed.

A reader (or an interrupted run) therefore sees either the previous complete file or the
new complete file, never half of one.
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Mapping
from pathlib import Path
from typing import Any

import numpy as np

from gimwatch.errors import OutputError

__all__ = [
    "prepare_directory",
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


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` through a temporary file in the same folder, then rename.

    Raises:
        OutputError: ``path`` is a directory, or its folder cannot be created or written
            (the previous file, if any, is left as it was).
    """
    path = Path(path)
    if path.is_dir():
        raise OutputError(str(path), "is a directory; give a file name")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    except OSError as exc:
        raise OutputError(str(path), f"cannot be written ({exc.strerror or exc})") from exc
    try:
        with os.fdopen(fd, "wb") as handle:
            handle.write(data)
        os.chmod(tmp, _FILE_MODE)  # mkstemp makes 0600 files; results are meant to be shared
        os.replace(tmp, path)
    except BaseException as exc:
        Path(tmp).unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise OutputError(str(path), f"cannot be written ({exc.strerror or exc})") from exc
        raise
    return path


def prepare_directory(path: str | Path) -> Path:
    """Create the folder ``path`` (and its parents) or raise :class:`OutputError`."""
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
    np.savez(buffer, **{k: np.asarray(v) for k, v in arrays.items()})
    return write_bytes_atomic(path, buffer.getvalue())
