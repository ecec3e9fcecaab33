"""Results folders against a hostile or careless neighbour: links at the lock's name, user
files whose names look like gimwatch's temporaries, read-only folders, a full disk.

Each case: exit 2 and one line naming the path, or a correct result; never a file of the
user's changed or deleted, never a file of gimwatch's left behind.
"""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import pytest

import gimwatch.output.folders as folders
from gimwatch.cli import main
from gimwatch.output import swap
from gimwatch.output.folders import MARKER, ResultsFolder
from gimwatch.output.swap import STAGING_RECORD

SCENE = """robot = "chain:2"
duration = 0.02
sample = 0.01
q = 0.1

[integrator]
method = "RK4"
dt = 0.005
"""


@pytest.fixture
def scene(tmp_path) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(SCENE, encoding="utf-8")
    return path


def _simulate(scene: Path, out: Path, capsys) -> tuple[int, str]:
    code = main(["simulate", str(scene), "-o", str(out)])
    return code, capsys.readouterr().err


def _one_error(err: str, path) -> None:
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("gimwatch: error: "), err
    assert str(path) in lines[0], err


def test_a_symlink_at_the_lock_name_is_refused_and_its_target_untouched(scene, tmp_path, capsys):
    victim = tmp_path / "someone_elses.txt"
    victim.write_text("precious", encoding="utf-8")
    lock = tmp_path / ".res.gimwatch-lock"
    lock.symlink_to(victim)
    code, err = _simulate(scene, tmp_path / "res", capsys)
    assert code == 2
    _one_error(err, lock)
    assert "symbolic link" in err
    assert victim.read_text(encoding="utf-8") == "precious" and lock.is_symlink()
    assert not (tmp_path / "res").exists()


def test_a_hard_link_or_a_user_file_at_the_lock_name_is_never_written(scene, tmp_path, capsys):
    victim = tmp_path / "notes.txt"
    victim.write_text("mine, and longer than a pid: " + "x" * 40, encoding="utf-8")
    lock = tmp_path / ".res.gimwatch-lock"
    os.link(victim, lock)
    code, err = _simulate(scene, tmp_path / "res", capsys)
    assert code == 2 and "not a gimwatch lock file" in err
    assert victim.read_text(encoding="utf-8").startswith("mine")


def test_a_lock_left_by_a_killed_writer_is_used_again(scene, tmp_path, capsys):
    (tmp_path / ".res.gimwatch-lock").write_text("12345", encoding="utf-8")
    code, err = _simulate(scene, tmp_path / "res", capsys)
    assert code == 0, err
    assert (tmp_path / "res" / MARKER).is_file()
    assert not (tmp_path / ".res.gimwatch-lock").exists()


def test_user_files_named_like_temporaries_survive_a_rewrite(scene, tmp_path, capsys):
    out = tmp_path / "res"
    assert _simulate(scene, out, capsys)[0] == 0
    inside = [out / "my.gimwatch-old-notes.txt", out / "x.gimwatch-staging-plan.md"]
    for path in inside:
        path.write_text("user", encoding="utf-8")
    beside = tmp_path / ".res.gimwatch-staging-mine"  # the user's folder, no staging record
    beside.mkdir()
    (beside / "data.csv").write_text("1,2", encoding="utf-8")
    old_beside = tmp_path / ".res.gimwatch-old-mine"
    old_beside.mkdir()
    code, err = _simulate(scene, out, capsys)
    assert code == 0, err
    for path in inside:
        assert path.read_text(encoding="utf-8") == "user"
    assert (beside / "data.csv").read_text(encoding="utf-8") == "1,2" and old_beside.is_dir()
    names = sorted(p.name for p in tmp_path.iterdir())
    assert names == sorted(
        ["res", "scene.toml", ".res.gimwatch-staging-mine", ".res.gimwatch-old-mine"]
    )


def test_a_read_only_results_folder_is_refused_and_nothing_is_left(scene, tmp_path, capsys):
    out = tmp_path / "res"
    assert _simulate(scene, out, capsys)[0] == 0
    before = sorted(p.name for p in out.iterdir())
    out.chmod(0o555)
    try:
        code, err = _simulate(scene, out, capsys)
    finally:
        out.chmod(0o755)
    assert code == 2 and "read-only results folder" in err
    _one_error(err, out)
    assert sorted(p.name for p in out.iterdir()) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["res", "scene.toml"]


def test_a_full_disk_at_the_lock_is_one_line_and_leaves_nothing(
    scene, tmp_path, capsys, monkeypatch
):
    real_write = os.write

    def full(fd, data):
        if os.readlink(f"/proc/self/fd/{fd}").endswith(".gimwatch-lock"):
            raise OSError(errno.ENOSPC, "No space left on device")
        return real_write(fd, data)

    monkeypatch.setattr(folders.os, "write", full)
    code, err = _simulate(scene, tmp_path / "res", capsys)
    assert code == 2 and "No space left on device" in err
    _one_error(err, tmp_path / "res")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


def _results_folder(path: Path, files: dict[str, str]) -> None:
    """A results folder as a previous gimwatch run left it."""
    with ResultsFolder(path, writer="test") as folder:
        for name, text in files.items():
            (folder.staging / name).write_text(text, encoding="utf-8")
        folder.commit()


def _recorded(path: Path, files: dict[str, str]) -> Path:
    """A folder a killed writer left: it holds the record a writer puts in what it creates."""
    path.mkdir()
    (path / STAGING_RECORD).write_text("12345\n", encoding="utf-8")
    for name, text in files.items():
        (path / name).write_text(text, encoding="utf-8")
    return path


def _listing(folder: Path) -> dict[str, str]:
    """Every file under ``folder`` (relative path -> text): the file system's own account."""
    return {
        str(p.relative_to(folder)): p.read_text(encoding="utf-8")
        for p in sorted(folder.rglob("*"))
        if p.is_file()
    }


def test_the_clean_up_removes_what_writers_recorded_and_nothing_else(tmp_path):
    """Beside ``out``: a killed writer's staging folder and moved-aside folder (both recorded)
    go; the user's folders and file named like them (no record), and the live staging folder
    of another results folder in the same parent (recorded, but not ``out``'s), stay."""
    out = tmp_path / "out"
    _results_folder(out, {"summary.json": "old"})
    _recorded(tmp_path / ".out.gimwatch-staging-dead", {"partial.npz": "half"})
    _recorded(tmp_path / ".out.gimwatch-old-dead", {"summary.json": "older"})
    (tmp_path / ".out.gimwatch-staging-mine").mkdir()
    (tmp_path / ".out.gimwatch-staging-mine" / "data.csv").write_text("1,2", encoding="utf-8")
    (tmp_path / ".out.gimwatch-old-mine").mkdir()
    (tmp_path / ".out.gimwatch-old-notes.txt").write_text("mine", encoding="utf-8")
    (tmp_path / "backup.gimwatch-old-2024").mkdir()
    _recorded(tmp_path / ".other.gimwatch-staging-live", {"series.npz": "being written"})
    users = {
        name: _listing(tmp_path / name)
        for name in (".out.gimwatch-staging-mine", ".other.gimwatch-staging-live")
    }
    _results_folder(out, {"summary.json": "new"})
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        ".other.gimwatch-staging-live",
        ".out.gimwatch-old-mine",
        ".out.gimwatch-old-notes.txt",
        ".out.gimwatch-staging-mine",
        "backup.gimwatch-old-2024",
        "out",
    ]
    for name, files in users.items():
        assert _listing(tmp_path / name) == files, name
    assert (tmp_path / ".out.gimwatch-old-notes.txt").read_text(encoding="utf-8") == "mine"
    assert sorted(p.name for p in out.iterdir()) == [MARKER, "summary.json"]
    assert (out / "summary.json").read_text(encoding="utf-8") == "new"
    assert json.loads((out / MARKER).read_text(encoding="utf-8"))["files"] == ["summary.json"]


def test_a_previous_folder_a_killed_writer_moved_aside_is_put_back(tmp_path, monkeypatch):
    """A writer killed between the two renames of the fallback swap left ``out`` moved aside
    (recorded before the rename): the next writer puts it back as it was, with no record in it
    (a record left there made every later two-rename swap fail with "File exists"), so a write
    that is not committed still leaves the previous results, and the next one succeeds."""
    out = tmp_path / "out"
    _results_folder(out, {"summary.json": "previous"})
    before = _listing(out)
    out.rename(tmp_path / ".out.gimwatch-old-0123abcd")
    (tmp_path / ".out.gimwatch-old-0123abcd" / STAGING_RECORD).write_text("1\n", "utf-8")
    with ResultsFolder(out, writer="test") as folder:
        (folder.staging / "summary.json").write_text("never committed", encoding="utf-8")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert _listing(out) == before
    monkeypatch.setattr(swap, "exchange", lambda a, b: False)  # the two-rename swap again
    _results_folder(out, {"summary.json": "new"})
    assert _listing(out)["summary.json"] == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
