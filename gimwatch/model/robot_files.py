"""Reading a robot description file: a regular file of bounded size, decoded as its XML says.

FIFOs and devices are refused (they could block or never end), sizes are bounded, and the
text is UTF-8 (a byte-order mark dropped) or the encoding its XML declaration names.
"""

from __future__ import annotations

import errno
import os
from pathlib import Path

from gimwatch.errors import URDFError

__all__ = ["MAX_URDF_BYTES", "decode_xml", "path_problem", "read_robot_file"]

#: The largest URDF file read (the biggest example-robot-data URDF is under 1 MB).
MAX_URDF_BYTES = 64 * 1024 * 1024


def read_robot_file(path: Path) -> str:
    """Read a URDF file; FIFOs and devices are refused (they could block or never end)."""
    try:
        if not path.exists():
            raise URDFError(str(path), path_problem(path))
        if path.is_dir():
            raise URDFError(str(path), "is a directory, not a URDF file")
        if not path.is_file():
            raise URDFError(str(path), "is not a regular file (a device, FIFO or socket)")
        size = path.stat().st_size
        if size > MAX_URDF_BYTES:
            raise URDFError(str(path), f"is {size} bytes, more than {MAX_URDF_BYTES} for a URDF")
        return decode_xml(path.read_bytes(), str(path))
    except OSError as exc:
        raise URDFError(str(path), f"cannot be read ({exc.strerror or exc})") from exc


def decode_xml(data: bytes, source: str) -> str:
    """XML bytes as text: UTF-8 without a byte-order mark, or the declared encoding.

    CAD exporters write ``<?xml version="1.0" encoding="ISO-8859-1"?>`` with accented
    names in comments; a file that is neither is refused naming the first bad byte.
    """
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        failure = exc
    _, found, rest = data[:200].decode("ascii", errors="replace").partition("encoding=")
    declared = rest[1:].split(rest[0], 1)[0] if found and rest[:1] in ("'", '"') else ""
    try:
        if declared and declared.lower().replace("_", "-") not in ("utf-8", "utf8"):
            return data.decode(declared)
    except (LookupError, UnicodeDecodeError):
        pass
    raise URDFError(
        source, f"is not UTF-8 text ({failure.reason} at byte {failure.start})"
    ) from failure


def path_problem(path: Path) -> str:
    """Why a path that does not exist cannot be opened: a symbolic-link loop, or no file."""
    try:
        os.stat(path)
    except OSError as exc:
        if exc.errno == errno.ELOOP:
            return "is a symbolic link loop (too many levels of symbolic links)"
    return "no such file"
