"""The API reference as rendered: no raw Sphinx roles, examples as code, each object once.

The site is built (``mkdocs build --strict``) into a temporary folder, as ``make docs`` does,
and its API pages are read as a browser would show them (tags stripped).
"""

from __future__ import annotations

import html
import importlib
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj|const|py:\w+):`?")
SOURCE_ROLE = re.compile(r":(?:func|class|meth|mod|data|attr|exc|obj|const):`")


@pytest.fixture(scope="module")
def api_pages(tmp_path_factory) -> dict[str, str]:
    site = tmp_path_factory.mktemp("site")
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "NO_MKDOCS_2_WARNING": "1"}
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "--quiet", "-d", str(site)],
        cwd=ROOT,
        env=environment,
        capture_output=True,
        text=True,
        check=False,
    )
    assert done.returncode == 0, done.stderr[-3000:]
    pages = {p.relative_to(site).as_posix(): p.read_text() for p in (site / "api").rglob("*.html")}
    assert len(pages) >= 6, sorted(pages)
    return pages


def _text(page: str) -> str:
    return html.unescape(re.sub(r"<[^>]+>", "", page))


def _resolve(dotted: str) -> object | None:
    parts = dotted.split(".")
    for k in range(len(parts), 0, -1):
        try:
            found = importlib.import_module(".".join(parts[:k]))
        except ImportError:
            continue
        for name in parts[k:]:
            found = getattr(found, name, None)
        return found
    return None


def test_no_raw_role_or_unresolved_reference_is_shown(api_pages):
    for name, page in api_pages.items():
        text = _text(page)
        shown = [text[max(0, m.start() - 40) : m.end() + 40] for m in ROLE.finditer(text)]
        assert not shown, f"{name}: raw Sphinx roles: {shown[:5]}"
        prose = _text(re.sub(r"<code>.*?</code>", "", page, flags=re.DOTALL))  # not examples
        assert "][gimwatch." not in prose, f"{name}: an unresolved cross-reference"


def test_cross_references_are_links(api_pages):
    page = api_pages["api/watch/index.html"]
    assert 'href="#gimwatch.watch.watch.Watch.sample"' in page  # Watch's docstring links it
    assert 'href="../model/#gimwatch.model.robots.Robot"' in page


def test_examples_render_as_code(api_pages):
    page = api_pages["api/metrics/index.html"]
    blocks = re.findall(r"<pre[^>]*>(.*?)</pre>", page, re.DOTALL)
    examples = [_text(b) for b in blocks if "estimator.calibrate" in _text(b)]
    assert examples, "the ScaledDiagonalRatio example is not a code block"
    lines = examples[0].splitlines()
    assert ">>> estimator = ScaledDiagonalRatio()" in lines  # one line each, not collapsed
    assert ">>> estimator(np.array([9.0, 1.0]))" in lines


def test_each_object_is_documented_once(api_pages):
    """An object re-exported by a package is shown where it is defined or re-exported, once."""
    where: dict[int, list[str]] = {}
    for page in api_pages.values():
        for ident in set(re.findall(r'<h[2-5] id="(gimwatch\.[\w.]+)"', page)):
            found = _resolve(ident)
            if inspect.isclass(found) or inspect.isfunction(found):
                where.setdefault(id(found), []).append(ident)
    twice = [sorted(ids) for ids in where.values() if len(ids) > 1]
    assert not twice, twice
    names = {ident.rsplit(".", 1)[-1] for ids in where.values() for ident in ids}
    assert {"Trajectory", "Watch", "load_robot", "LeanModel", "Alarm"} <= names


def test_no_sphinx_role_in_the_sources():
    """Docstrings use mkdocstrings cross-references ([`x`][gimwatch.m.x]) or backticks."""
    found = [
        f"{path.relative_to(ROOT)}:{text[: m.start()].count(chr(10)) + 1}"
        for path in sorted((ROOT / "gimwatch").rglob("*.py"))
        for text in [path.read_text(encoding="utf-8")]
        for m in SOURCE_ROLE.finditer(text)
    ]
    assert not found, found
