"""The lock of a results folder: an exclusive ``flock`` on ``.NAME.gimwatch-lock`` beside it.

A second writer of the same folder refuses at once; the lock file is created with
``O_EXCL | O_NOFOLLOW`` and never written through a symbolic link or into a file gimwatch
did not leave there (a hard link, a file of the user's).
"""

from __future__ import annotations

import errno
import fcntl
import os
import stat
from pathlib import Path

from gimwatch.errors import OutputError
from gimwatch.output.swap import LOCK

__all__ = ["FolderLock"]


def _problem(exc: OSError) -> str:
    return f"cannot be written ({exc.strerror or exc})"


class FolderLock:
    """An exclusive ``flock`` on ``.NAME.gimwatch-lock`` beside a results folder."""

    def __init__(self, target: Path, shown: str) -> None:
        self.path = target.parent / f".{target.name}{LOCK}"
        while True:
            fd = self._open(shown)
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except OSError as exc:
                holder = os.read(fd, 32).decode(errors="replace").strip()
                os.close(fd)
                if exc.errno not in (errno.EWOULDBLOCK, errno.EAGAIN):
                    raise OutputError(shown, _problem(exc)) from exc
                who = f" (pid {holder})" if holder.isdigit() else ""
                raise OutputError(
                    shown,
                    f"is being written by another gimwatch process{who}; "
                    "nothing was written: wait for it to finish or give another folder",
                ) from None
            try:  # the holder before us may have removed the file after we opened it
                same = os.path.samestat(os.fstat(fd), os.stat(self.path))
            except FileNotFoundError:
                same = False
            if same:
                break
            os.close(fd)
        self.fd = fd
        try:
            os.ftruncate(fd, 0)
            os.write(fd, str(os.getpid()).encode())
        except OSError as exc:  # a full disk: one line, and the lock file is not left behind
            self.release()
            raise OutputError(shown, _problem(exc)) from exc

    def _open(self, shown: str) -> int:
        """A descriptor of the lock file, never through a symbolic link.

        A lock file left by a killed writer is used again only when it is one: a regular
        file of ours with one link holding at most a pid. Anything else at that name (a link
        aimed at another user's file, a file of the user's) is refused, never written to.
        """
        flags = os.O_RDWR | os.O_CLOEXEC | os.O_NOFOLLOW
        try:
            return os.open(self.path, flags | os.O_CREAT | os.O_EXCL, 0o644)
        except FileExistsError:
            pass
        except OSError as exc:
            raise OutputError(shown, _problem(exc)) from exc
        try:
            fd = os.open(self.path, flags)
        except FileNotFoundError:  # removed since: create it again
            return self._open(shown)
        except OSError as exc:
            problem = (
                "is a symbolic link, not a gimwatch lock; nothing was written: remove it"
                if exc.errno == errno.ELOOP
                else _problem(exc)
            )
            raise OutputError(str(self.path), problem) from exc
        info = os.fstat(fd)
        if not (
            stat.S_ISREG(info.st_mode)
            and info.st_nlink == 1
            and info.st_uid == os.geteuid()
            and info.st_size <= 32
        ):
            os.close(fd)
            raise OutputError(
                str(self.path), "is not a gimwatch lock file; nothing was written: remove it"
            )
        return fd

    def release(self) -> None:
        """Remove the lock file, then unlock (in this order: see the loop above)."""
        try:
            os.unlink(self.path)
        except OSError:
            pass
        os.close(self.fd)
