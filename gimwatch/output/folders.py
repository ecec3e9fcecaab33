"""Results folders that never destroy what gimwatch did not write.

A results folder holds a marker file, `MARKER`, naming the command that wrote it and
the entries it wrote. `ResultsFolder` writes one:

1. the target is checked: absent, empty, or a folder holding the marker; anything else (a
   folder of the user's files, a regular file, a device, a FIFO) is refused with an
   [`OutputError`][gimwatch.errors.OutputError], before any work;
2. a lock (``fcntl.flock`` on ``.NAME.gimwatch-lock`` beside the folder) makes a second
   writer of the same folder refuse at once instead of mixing results;
3. the files are written into a staging folder beside the target (``.NAME.gimwatch-staging-*``);
4. `ResultsFolder.commit` writes the marker, links into the staging folder the entries
   of the previous folder that gimwatch did not write (the user's notes, another command's
   sub-folders), then swaps the two folders in one step (``renameat2(RENAME_EXCHANGE)`` on
   Linux, two renames elsewhere) and deletes the previous one.

A reader therefore sees the previous complete folder or the new complete one. SIGINT and
SIGTERM are held (noted, then re-delivered) while the file system changes state, so a signal
never leaves a half-swapped folder or a stray staging folder; without a commit, the staging
folder, the lock and any parent folder created for the target are removed.
"""

from __future__ import annotations

import json
import os
import shutil
import stat
import tempfile
from collections.abc import Iterable
from pathlib import Path
from types import TracebackType

from gimwatch.errors import OutputError
from gimwatch.output.atomic import describe_kind, signals_held, write_json_atomic
from gimwatch.output.lock import FolderLock
from gimwatch.output.swap import (
    STAGING,
    STAGING_RECORD,
    carry,
    mark_staging,
    remove_stale,
    swap,
)

__all__ = [
    "MARKER",
    "Reservation",
    "ResultsFolder",
    "check_folder_target",
    "is_results_folder",
    "write_marker",
]

#: The file that makes a folder a gimwatch results folder.
MARKER = ".gimwatch-results.json"


def _problem(exc: OSError) -> str:
    return f"cannot be written ({exc.strerror or exc})"


def is_results_folder(path: str | Path) -> bool:
    """True when ``path`` is a folder holding the `MARKER` file."""
    marker = Path(path) / MARKER
    try:
        return stat.S_ISREG(os.lstat(marker).st_mode)
    except OSError:
        return False


def _written_by_gimwatch(folder: Path) -> set[str]:
    """The entries the marker of ``folder`` lists (none when it cannot be read)."""
    try:
        record = json.loads((folder / MARKER).read_text(encoding="utf-8"))
        return {str(name) for name in record.get("files", [])}
    except (OSError, ValueError, AttributeError):
        return set()


def write_marker(folder: Path, writer: str, files: Iterable[str] | None = None) -> Path:
    """Write the `MARKER` of ``folder``: its writer and the entries it wrote.

    Args:
        folder: The folder.
        writer: The command that wrote it (``"simulate"``, ``"survey"``, ...).
        files: The entries gimwatch wrote; default: every entry now in ``folder``.
    """
    if files is None:
        files = {p.name for p in folder.iterdir()} - {MARKER}
    record = {"format": "gimwatch-results/1", "writer": writer, "files": sorted(files)}
    return write_json_atomic(folder / MARKER, record)


def check_folder_target(path: str | Path) -> Path:
    """The absolute path (symbolic links resolved) that a results folder may be written to.

    Raises:
        OutputError: ``path`` exists and is not a folder, or is a folder that is neither
            empty nor a gimwatch results folder.
    """
    target = Path(os.path.realpath(os.path.abspath(path)))
    mode = _target_mode(target, str(path))
    if mode is None:
        return target
    _check_is_folder(mode, str(path))
    if is_results_folder(target):
        if not mode & stat.S_IWUSR:
            raise OutputError(
                str(path),
                f"is a read-only results folder (mode {stat.S_IMODE(mode):04o}): its owner "
                "protected it; nothing was written: make it writable or give another folder",
            )
        return target
    try:
        empty = not any(os.scandir(target))
    except OSError as exc:
        raise OutputError(str(path), f"cannot be read ({exc.strerror or exc})") from exc
    if not empty:
        raise OutputError(
            str(path),
            f"is a folder that is not empty and not a gimwatch results folder (no {MARKER}); "
            "nothing was written: give a new or empty folder",
        )
    return target


def _target_mode(target: Path, shown: str) -> int | None:
    """``lstat``'s mode of a results folder's target, None if there is nothing there yet."""
    try:
        return os.lstat(target).st_mode
    except FileNotFoundError:
        return None
    except NotADirectoryError as exc:  # a file where a parent folder should be
        for parent in target.parents:
            if parent.exists() and not parent.is_dir():
                raise OutputError(
                    str(parent), "is a file, not a folder; give a folder name"
                ) from exc
        raise OutputError(shown, _problem(exc)) from exc
    except OSError as exc:
        raise OutputError(shown, _problem(exc)) from exc


def _check_is_folder(mode: int, shown: str) -> None:
    """Refuse a target that exists and is not a folder (a dangling link, a file, a FIFO...)."""
    if stat.S_ISLNK(mode):
        raise OutputError(shown, "is a symbolic link that cannot be resolved (a loop?)")
    if stat.S_ISREG(mode):
        raise OutputError(shown, "is a file, not a folder; give a folder name")
    if not stat.S_ISDIR(mode):
        raise OutputError(shown, f"is a {describe_kind(mode)}, not a folder; give a folder name")


#: Folders this process holds: target -> [lock, holders, parents created for it].
_HELD: dict[Path, list] = {}


def _make_parents(folder: Path, shown: str) -> list[Path]:
    """Create ``folder`` and its missing parents; return those created, outermost first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        if folder.parent == folder:
            break
        folder = folder.parent
    created: list[Path] = []
    for path in reversed(missing):
        try:
            path.mkdir()
        except OSError as exc:
            _remove_parents(created)
            raise OutputError(shown, _problem(exc)) from exc
        created.append(path)
    return created


def _remove_parents(created: list[Path]) -> None:
    for path in reversed(created):
        try:
            path.rmdir()
        except OSError:
            break


class Reservation:
    """Hold the right to write the results folder ``path``: checked, parents made, locked.

    Re-entrant within a process (a command reserves its folder before computing; the
    writer it calls reserves it again). On leaving without a commit, the parents created
    for it are removed again (when empty).
    """

    def __init__(self, path: str | Path) -> None:
        self.shown = str(path)
        self.target = check_folder_target(path)
        self.committed = False

    def __enter__(self) -> Reservation:
        held = False
        try:
            with signals_held():
                if self.target in _HELD:
                    _HELD[self.target][1] += 1
                else:
                    created = _make_parents(self.target.parent, self.shown)
                    try:
                        lock = FolderLock(self.target, self.shown)
                    except BaseException:
                        _remove_parents(created)
                        raise
                    _HELD[self.target] = [lock, 1, created]
                held = True
            check_folder_target(self.target)  # it may have changed before we held the lock
        except BaseException:  # a refusal, or a signal delivered on leaving signals_held
            if held:
                Reservation.__exit__(self, None, None, None)
            raise
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        with signals_held():
            held = _HELD[self.target]
            held[1] -= 1
            if self.committed:
                held[2] = []  # the parents now hold a result: keep them
            if held[1] == 0:
                del _HELD[self.target]
                held[0].release()
                if not self.target.exists():
                    _remove_parents(held[2])


class ResultsFolder(Reservation):
    """Write a results folder through a staging folder; `commit` puts it in place.

    Example::

        with ResultsFolder("out", writer="simulate") as folder:
            (folder.staging / "summary.json").write_text("{}")
            folder.commit()

    Args:
        path: The results folder.
        writer: The command writing it (recorded in the marker).
        keep_previous: Also keep the previous folder's gimwatch entries that this run does
            not write (``bench`` runs a few sections into a folder of all of them); by
            default only the entries gimwatch did not write are kept.
    """

    def __init__(self, path: str | Path, *, writer: str, keep_previous: bool = False) -> None:
        super().__init__(path)
        self.writer, self.keep_previous = writer, keep_previous
        self.staging: Path | None = None

    def __enter__(self) -> ResultsFolder:
        super().__enter__()
        try:
            with signals_held():
                prefix = f".{self.target.name}{STAGING}"
                self.staging = Path(tempfile.mkdtemp(prefix=prefix, dir=self.target.parent))
                mark_staging(self.staging)
            remove_stale(self.target, keep=self.staging, marker=MARKER)
        except BaseException as exc:  # a signal delivered on leaving signals_held, included
            self.__exit__(type(exc), exc, exc.__traceback__)  # raises OutputError for OSError
            raise
        return self

    def __exit__(
        self,
        kind: type[BaseException] | None,
        exc: BaseException | None,
        tb: TracebackType | None,
    ) -> None:
        with signals_held():  # one block: a signal cannot come between the two clean-ups
            if not self.committed and self.staging is not None:
                shutil.rmtree(self.staging, ignore_errors=True)
            super().__exit__(kind, exc, tb)
        staging = str(self.staging)
        if isinstance(exc, OutputError) and exc.path.startswith(staging):
            raise OutputError(self.shown, exc.problem) from exc  # name the folder, not its copy
        if isinstance(exc, OSError) and not isinstance(exc, OutputError):
            raise OutputError(self.shown, _problem(exc)) from exc

    def commit(self) -> Path:
        """Put the staging folder in place of the results folder; return the folder's path.

        Raises:
            OutputError: The folder cannot be written; the previous one is left as it was.
        """
        if self.staging is None:
            raise RuntimeError("commit() outside the with block")
        try:
            os.chmod(self.staging, 0o777 & ~_umask())  # mkdtemp makes 0700 folders
            # the record stays until the swap is done (swap): a writer killed before then
            # leaves a folder the next writer recognises and clears
            written = {p.name for p in self.staging.iterdir()} - {MARKER, STAGING_RECORD}
            previous = self.target if self.target.is_dir() else None
            ours = _written_by_gimwatch(previous) if previous else set()
            carried = set()
            for entry in os.scandir(previous) if previous else ():
                name = entry.name
                if name in written or name in (MARKER, STAGING_RECORD):
                    continue
                if name in ours and not self.keep_previous:
                    continue
                carry(Path(entry.path), self.staging / name)
                carried.add(name)
            write_marker(self.staging, self.writer, written | (carried & ours))
            with signals_held():
                check_folder_target(self.target)
                swap(self.staging, self.target)
                self.committed = True
                _remove_previous(self.staging)
        except OSError as exc:
            raise OutputError(self.shown, _problem(exc)) from exc
        except OutputError as exc:  # name the folder, not its staging copy
            raise OutputError(self.shown, exc.problem) from exc
        return self.target


def _remove_previous(folder: Path) -> None:
    """Delete the previous results folder (now at the staging path), read-only parts too."""

    def writable_again(function, path, _excinfo) -> None:  # a sub-folder made read-only
        try:
            os.chmod(os.path.dirname(path), stat.S_IRWXU)
            function(path)
        except OSError:
            pass

    shutil.rmtree(folder, onerror=writable_again)


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask
