"""gimwatch's numba kernels are cached on disk and a compilation says so, once, on stderr."""

from __future__ import annotations

import ast
import logging
from pathlib import Path

import numpy as np
from numba.core import event

from gimwatch.jit import COMPILE_NOTE, NOTE, CompileNote, njit

ROOT = Path(__file__).resolve().parents[1]


def _kernel(module: str):
    namespace = {"__name__": module}
    exec("def add_one(x):\n    return x + 1.0\n", namespace)
    return njit(cache=False)(namespace["add_one"])


def test_the_first_gimwatch_compilation_logs_one_line(caplog, monkeypatch):
    monkeypatch.setattr(NOTE, "noted", True)  # the process's own note, maybe spent already
    note = CompileNote()
    event.register("numba:compile", note)
    caplog.set_level(logging.WARNING, logger="gimwatch")
    try:
        assert _kernel("elsewhere.module")(np.float64(1.0)) == 2.0  # not ours: no note
        assert not caplog.records
        assert _kernel("gimwatch.probe")(np.float64(1.0)) == 2.0
        assert _kernel("gimwatch.probe_two")(np.float64(2.0)) == 3.0
        assert [r.getMessage() for r in caplog.records] == [
            COMPILE_NOTE.format(where="numba's cache folder")
        ]
        assert caplog.records[0].name == "gimwatch"
    finally:
        event.unregister("numba:compile", note)


def test_every_kernel_is_cached_and_compiled_through_gimwatch_jit():
    """A kernel compiled with numba.njit directly would get neither the cache nor the note."""
    for path in sorted((ROOT / "gimwatch").rglob("*.py")):
        if path.name == "jit.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.ImportFrom) and node.module == "numba":
                raise AssertionError(f"{path}: import njit from gimwatch.jit, not numba")
            if isinstance(node, ast.keyword) and node.arg == "cache":
                assert getattr(node.value, "value", True) is True, f"{path}: cache=False"


def test_no_writable_cache_folder_compiles_without_cache(monkeypatch):
    import gimwatch.jit as jit

    real = jit.numba.njit
    asked = []

    def refusing(**options):
        asked.append(options["cache"])
        if options["cache"]:
            raise RuntimeError("cannot cache function 'f': no locator available for file 'x'")
        return real(**options)

    monkeypatch.setattr(jit.numba, "njit", refusing)

    @jit.njit
    def twice(x):
        return 2.0 * x

    assert twice(np.float64(2.0)) == 4.0 and asked == [True, False]


def test_the_compile_note_comes_once_per_install(caplog, monkeypatch, tmp_path):
    """A second process of the same install (a new note, the same marker) says nothing."""
    monkeypatch.setattr(NOTE, "noted", True)
    marker = tmp_path / "cache" / "noted"
    caplog.set_level(logging.WARNING, logger="gimwatch")
    for process in range(2):
        note = CompileNote(marker)
        event.register("numba:compile", note)
        try:
            assert _kernel(f"gimwatch.probe_install_{process}")(np.float64(1.0)) == 2.0
        finally:
            event.unregister("numba:compile", note)
        assert marker.exists()
    assert len(caplog.records) == 1
    assert "once per install" in caplog.records[0].getMessage()
    assert "10-40 s" in caplog.records[0].getMessage()
