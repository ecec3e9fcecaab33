"""A measured file's fingerprint: digests that ignore docs, catch code, and list the imports."""

from __future__ import annotations

import pytest

from gimwatch.bench.freshness import (
    FINGERPRINT_KEY,
    PACKAGE_ROOT,
    fingerprint,
    module_digest,
    modules_imported_by,
    stale_modules,
)

CODE = '''"""A module."""

import math


def area(r):
    """Disc area."""
    return math.pi * r * r  # pi r^2
'''


def test_docs_and_comments_do_not_change_the_digest_code_does(tmp_path):
    path = tmp_path / "m.py"
    path.write_text(CODE)
    before = module_digest(path)
    path.write_text(CODE.replace("Disc area.", "The area of a disc.").replace("# pi r^2", ""))
    assert module_digest(path) == before
    path.write_text(CODE.replace("\n\n\ndef", "\n\ndef"))  # formatting
    assert module_digest(path) == before
    path.write_text(CODE.replace("r * r", "r ** 2"))
    assert module_digest(path) != before


def test_stale_modules_names_the_changed_and_the_missing(tmp_path):
    package = tmp_path / "gimwatch"
    package.mkdir()
    for name in ("a.py", "b.py", "c.py"):
        (package / name).write_text(CODE)
    record = fingerprint(sorted(package.glob("*.py")))
    assert list(record["modules"]) == ["gimwatch/a.py", "gimwatch/b.py", "gimwatch/c.py"]
    assert stale_modules(record, tmp_path) == []
    (package / "b.py").write_text(CODE.replace("math.pi", "3.14"))
    (package / "c.py").unlink()
    assert stale_modules(record, tmp_path) == ["gimwatch/b.py", "gimwatch/c.py"]
    assert fingerprint(sorted(package.glob("*.py")))["digest"] != record["digest"]


def test_the_probe_lists_what_a_command_imports(tmp_path):
    analyze = modules_imported_by([["-m", "gimwatch", "analyze", "chain:3"]], tmp_path)
    names = {path.as_posix().rsplit("/gimwatch/", 1)[-1] for path in analyze}  # any clone name
    assert {"cli/analyze.py", "metrics/dense_analysis.py", "model/robots.py"} <= names
    assert "simulation/simulate.py" not in names  # only what the path imports
    scripted = modules_imported_by([["-c", "import gimwatch.errors"]], tmp_path)
    assert [p.name for p in scripted] == ["__init__.py", "_version.py", "errors.py"]


def test_a_failing_probe_is_an_error(tmp_path):
    with pytest.raises(RuntimeError, match="failed"):
        modules_imported_by([["-m", "gimwatch", "analyze", "no-such-robot"]], tmp_path)


def test_a_bench_run_writes_the_measured_modules_into_each_table(tmp_path):
    """A quick section's JSON tables carry the digests of what the process ran (not the CLI)."""
    import json

    from gimwatch.bench import run_bench

    run_bench(["dynamics"], tmp_path / "out", quick=True)
    record = json.loads((tmp_path / "out" / "dynamics.json").read_text(encoding="utf-8"))
    modules = record[FINGERPRINT_KEY]["modules"]
    assert "gimwatch/bench/dynamics.py" in modules and "gimwatch/denoc/lean.py" in modules
    assert not any(name.startswith(("gimwatch/cli/", "gimwatch/output/")) for name in modules)
    assert stale_modules(record[FINGERPRINT_KEY]) == []
    for name, digest in modules.items():  # each digest is the module's code as it is now
        assert digest == module_digest(PACKAGE_ROOT / name)
