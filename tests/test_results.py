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
