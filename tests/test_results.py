import errno
import json
import os

import numpy as np
import pytest

from gimwatch.errors import OutputError
from gimwatch.output import atomic as results
from gimwatch.output.atomic import write_json_atomic, write_npz_atomic, write_text_atomic


class _Interrupted(KeyboardInterrupt):
    pass


def test_interrupted_write_leaves_the_previous_file_intact(tmp_path, monkeypatch):
    path = tmp_path / "summary.json"
    write_json_atomic(path, {"kappa": 1074.44})
    real_fdopen = os.fdopen

    def half_then_interrupt(fd, mode):
        handle = real_fdopen(fd, mode)
        real_write = handle.write

        def write(data):
            real_write(data[: len(data) // 2])
            handle.flush()
            raise _Interrupted

        handle.write = write
        return handle

    monkeypatch.setattr(results.os, "fdopen", half_then_interrupt)
    with pytest.raises(_Interrupted):
        write_json_atomic(path, {"kappa": 2.0, "padding": "x" * 10_000})
    assert json.loads(path.read_text()) == {"kappa": 1074.44}
    assert [p.name for p in tmp_path.iterdir()] == ["summary.json"]  # no temporary left


def test_interrupt_before_the_rename_leaves_the_previous_npz(tmp_path, monkeypatch):
    path = tmp_path / "series.npz"
    write_npz_atomic(path, {"kappa": np.arange(3.0)})
    monkeypatch.setattr(results.os, "replace", lambda src, dst: (_ for _ in ()).throw(_Interrupted))
    with pytest.raises(_Interrupted):
        write_npz_atomic(path, {"kappa": np.arange(5.0)})
    with np.load(path, allow_pickle=False) as data:
        np.testing.assert_array_equal(data["kappa"], np.arange(3.0))
    assert [p.name for p in tmp_path.iterdir()] == ["series.npz"]


def test_a_completed_write_replaces_the_file(tmp_path):
    path = tmp_path / "a" / "b.txt"
    write_text_atomic(path, "old")
    write_text_atomic(path, "new")
    assert path.read_text() == "new"


def test_unwritable_targets_raise_output_error(tmp_path):
    with pytest.raises(OutputError, match="is a directory; give a file name"):
        write_text_atomic(tmp_path, "x")
    (tmp_path / "file").write_text("keep")
    with pytest.raises(OutputError, match=r"file/x.txt: cannot be written"):
        write_text_atomic(tmp_path / "file" / "x.txt", "x")
    assert (tmp_path / "file").read_text() == "keep"


def _names(folder) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def test_successful_writes_leave_exactly_their_files(tmp_path):
    """Each writer, on a new name and over an old file: the folder holds the files, nothing
    else (a temporary copied into place instead of renamed would stay beside them)."""
    for _round in range(2):
        write_json_atomic(tmp_path / "summary.json", {"kappa": 1074.44, "series": np.arange(3)})
        write_text_atomic(tmp_path / "notes.txt", "κ ≈ 1074\n")
        write_npz_atomic(tmp_path / "series.npz", {"kappa": np.arange(4.0)})
        assert _names(tmp_path) == ["notes.txt", "series.npz", "summary.json"]
    assert json.loads((tmp_path / "summary.json").read_text()) == {
        "kappa": 1074.44,
        "series": [0, 1, 2],
    }
    assert (tmp_path / "notes.txt").read_text(encoding="utf-8") == "κ ≈ 1074\n"
    with np.load(tmp_path / "series.npz", allow_pickle=False) as data:
        np.testing.assert_array_equal(data["kappa"], np.arange(4.0))


def test_a_value_json_cannot_hold_changes_nothing(tmp_path):
    path = tmp_path / "summary.json"
    write_json_atomic(path, {"kappa": 1074.44})
    before = path.read_bytes()
    with pytest.raises(TypeError, match="not JSON serializable"):
        write_json_atomic(path, {"kappa": 2.0, "robot": object()})
    assert path.read_bytes() == before
    assert _names(tmp_path) == ["summary.json"]


@pytest.mark.parametrize("call", ["replace", "chmod", "fdopen"])
def test_a_write_failing_mid_way_keeps_the_previous_file_and_no_temporary(
    tmp_path, monkeypatch, call
):
    """A full disk at the write, at the permissions or at the rename: the error names the
    file, the previous content stays byte for byte, the temporary is removed."""
    path = tmp_path / "series.npz"
    write_npz_atomic(path, {"kappa": np.arange(3.0)})
    before = path.read_bytes()

    def full_disk(*args, **kwargs):
        if call == "fdopen":
            os.close(args[0])  # the descriptor mkstemp opened: not leaked by the test
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(results.os, call, full_disk)
    with pytest.raises(OutputError) as info:
        write_npz_atomic(path, {"kappa": np.arange(5.0)})
    assert str(info.value) == f"{path}: cannot be written (No space left on device)"
    monkeypatch.undo()
    assert path.read_bytes() == before
    assert _names(tmp_path) == ["series.npz"]


def test_a_failed_first_write_leaves_the_folder_empty(tmp_path, monkeypatch):
    def refused(src, dst):
        raise OSError(errno.EACCES, "Permission denied")

    monkeypatch.setattr(results.os, "replace", refused)
    with pytest.raises(OutputError, match="cannot be written \\(Permission denied\\)"):
        write_text_atomic(tmp_path / "report.md", "# report\n")
    assert _names(tmp_path) == []
