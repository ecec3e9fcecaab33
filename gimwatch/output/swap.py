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

__all__ = [
    "LOCK",
    "OLD",
    "STAGING",
    "STAGING_RECORD",
    "carry",
    "exchange",
    "is_temporary",
    "mark_staging",
    "remove_stale",
    "swap",
]

#: Name parts of the files a writer keeps beside a results folder ``NAME``:
#: ``.NAME.gimwatch-lock``, ``.NAME.gimwatch-staging-*``, ``.NAME.gimwatch-old-*``.
LOCK, STAGING, OLD = ".gimwatch-lock", ".gimwatch-staging-", ".gimwatch-old-"
_RENAME_EXCHANGE, _AT_FDCWD = 2, -100


#: The record a writer puts in each staging folder it creates: its own temporaries are
#: recognised by this record, never by a name (a user's file may contain any name).
STAGING_RECORD = ".gimwatch-staging-record"


def is_temporary(path: Path) -> bool:
    """True for a staging folder a gimwatch writer made (not a symlink, holding its record)."""
    try:
        return stat.S_ISDIR(os.lstat(path).st_mode) and stat.S_ISREG(
            os.lstat(path / STAGING_RECORD).st_mode
        )
    except OSError:
        return False


def mark_staging(folder: Path) -> None:
    """Write the record that makes ``folder`` a staging folder of this writer."""
    descriptor = os.open(
        folder / STAGING_RECORD, os.O_WRONLY | os.O_CREAT | os.O_EXCL | os.O_NOFOLLOW, 0o644
    )
    try:
        os.write(descriptor, f"{os.getpid()}\n".encode())
    finally:
        os.close(descriptor)


def carry(source: Path, destination: Path) -> None:
    """Rebuild ``source`` at ``destination`` with hard links (copies where links fail)."""
    mode = os.lstat(source).st_mode
    if stat.S_ISDIR(mode):
        os.mkdir(destination)
        for entry in os.scandir(source):
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
    """Put ``staging`` at ``target``; afterwards ``staging`` holds the previous folder, if any.

    During the swap both folders hold the staging record, and the previous folder keeps it:
    whenever the writer is killed (SIGKILL cannot be held), what it leaves beside ``target``
    carries the record, so the next writer's `remove_stale` finds it. (Without it, the
    previous folder sat at the staging path after the exchange, hidden for good.) The
    record is then taken out of the new folder at ``target``.
    """
    if not target.exists():
        os.rename(staging, target)
        (target / STAGING_RECORD).unlink(missing_ok=True)
        return
    (target / STAGING_RECORD).unlink(missing_ok=True)  # one a killed writer left in it
    mark_staging(target)
    try:
        if not exchange(staging, target):
            old = target.parent / f".{target.name}{OLD}{secrets.token_hex(4)}"
            os.rename(target, old)
            try:
                os.rename(staging, target)
            except BaseException:
                os.rename(old, target)
                raise
            os.rename(old, staging)
    except BaseException:
        (target / STAGING_RECORD).unlink(missing_ok=True)  # the previous folder as it was
        raise
    (target / STAGING_RECORD).unlink(missing_ok=True)


def remove_stale(target: Path, *, keep: Path, marker: str = "") -> None:
    """Clear what a killed writer of ``target`` left (we hold its lock).

    Its staging folders are removed, and so is a previous folder it had swapped out (the
    swap was done: the new folder is complete at ``target``, and the user's entries of the
    previous one were linked into it). When nothing is at ``target``, a folder it left that
    holds ``marker`` (a complete results folder, the previous one or the new one) is put
    back there instead, without the record. A staging record left in ``target`` itself is
    removed. Only folders a writer made are touched: they hold the staging record (`swap`
    writes it into the previous folder before the exchange); anything else with such a name
    is the user's and is left alone.
    """
    prefixes = (f".{target.name}{STAGING}", f".{target.name}{OLD}")
    try:
        entries = sorted(os.scandir(target.parent), key=lambda e: e.name)
    except OSError:
        return
    if is_temporary(target):
        (target / STAGING_RECORD).unlink(missing_ok=True)
    for entry in entries:
        path = Path(entry.path)
        if not entry.name.startswith(prefixes) or path == keep or not is_temporary(path):
            continue
        with signals_held():
            complete = OLD in entry.name or (marker and os.path.isfile(path / marker))
            if complete and not os.path.lexists(target):
                try:
                    os.rename(entry.path, target)
                    # as it was: a record left in it would make the next fallback swap fail
                    (target / STAGING_RECORD).unlink(missing_ok=True)
                    continue
                except OSError:
                    pass
            shutil.rmtree(entry.path, ignore_errors=True)
