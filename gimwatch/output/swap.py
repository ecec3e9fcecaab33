"""Swapping a results folder into place: the steps `gimwatch.output.folders` takes.

The staging folder and the previous one are exchanged in one step where the system can
(``renameat2(RENAME_EXCHANGE)``, Linux), else by two renames; the entries of the previous
folder that are kept are rebuilt in the staging folder with hard links; what a writer killed
half way left behind is cleared by the next writer of the same folder.
"""

from __future__ import annotations

import ctypes
import errno
import os
import secrets
import shutil
import stat
from pathlib import Path

from gimwatch.output.atomic import signals_held

__all__ = ["LOCK", "OLD", "STAGING", "carry", "exchange", "is_temporary", "remove_stale", "swap"]

#: Name parts of the files a writer keeps beside a results folder ``NAME``:
#: ``.NAME.gimwatch-lock``, ``.NAME.gimwatch-staging-*``, ``.NAME.gimwatch-old-*``.
LOCK, STAGING, OLD = ".gimwatch-lock", ".gimwatch-staging-", ".gimwatch-old-"
_RENAME_EXCHANGE, _AT_FDCWD = 2, -100


def is_temporary(name: str) -> bool:
    """True for the lock, staging and old folders a writer keeps beside a results folder."""
    return LOCK in name or STAGING in name or OLD in name


def carry(source: Path, destination: Path) -> None:
    """Rebuild ``source`` at ``destination`` with hard links (copies where links fail)."""
    mode = os.lstat(source).st_mode
    if stat.S_ISDIR(mode):
        os.mkdir(destination)
        for entry in os.scandir(source):
            if not is_temporary(entry.name):
                carry(Path(entry.path), destination / entry.name)
        shutil.copystat(source, destination, follow_symlinks=False)
    elif stat.S_ISLNK(mode):
        os.symlink(os.readlink(source), destination)
    else:
        try:
            os.link(source, destination, follow_symlinks=False)
        except OSError:
            if not stat.S_ISREG(mode):
                raise
            shutil.copy2(source, destination)


def exchange(a: Path, b: Path) -> bool:
    """Swap two paths in one step (Linux ``renameat2``); False where that is not available."""
    try:
        renameat2 = ctypes.CDLL(None, use_errno=True).renameat2
    except (OSError, AttributeError):
        return False
    result = renameat2(_AT_FDCWD, os.fsencode(a), _AT_FDCWD, os.fsencode(b), _RENAME_EXCHANGE)
    if result == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.EINVAL, errno.ENOSYS, errno.EOPNOTSUPP):
        return False
    raise OSError(code, os.strerror(code), str(b))


def swap(staging: Path, target: Path) -> None:
    """Put ``staging`` at ``target``; afterwards ``staging`` holds the previous folder, if any."""
    if not target.exists():
        os.rename(staging, target)
        return
    if exchange(staging, target):
        return
    old = target.parent / f".{target.name}{OLD}{secrets.token_hex(4)}"
    os.rename(target, old)
    try:
        os.rename(staging, target)
    except BaseException:
        os.rename(old, target)
        raise
    os.rename(old, staging)


def remove_stale(target: Path, *, keep: Path) -> None:
    """Clear what a killed writer of ``target`` left (we hold its lock).

    Its staging folders are removed; a previous folder it had moved aside (the two-rename
    swap) is put back when nothing took its place, else removed.
    """
    prefixes = (f".{target.name}{STAGING}", f".{target.name}{OLD}")
    try:
        entries = sorted(os.scandir(target.parent), key=lambda e: e.name)
    except OSError:
        return
    for entry in entries:
        if not entry.name.startswith(prefixes) or Path(entry.path) == keep:
            continue
        with signals_held():
            if OLD in entry.name and not os.path.lexists(target):
                try:
                    os.rename(entry.path, target)
                    continue
                except OSError:
                    pass
            shutil.rmtree(entry.path, ignore_errors=True)
