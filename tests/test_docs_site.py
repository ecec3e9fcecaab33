"""The documentation site builds with no warning, and every link and image of it resolves.

The site is built into a temporary folder with ``mkdocs build --strict`` (no ``--quiet``), then
every ``src=`` and ``href=`` of its HTML pages that points inside the site is resolved against
the page's own folder. Committed text must not carry a path of the machine that wrote it.
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from html.parser import HTMLParser
from pathlib import Path
from urllib.parse import unquote, urlsplit

import pytest

from gimwatch.bench.report import update_readme

ROOT = Path(__file__).resolve().parents[1]
MACHINE_ROOTS = ("/work/", "/root/", "/home/", "/tmp/")
MARKDOWN_LINK = re.compile(r"!?\[[^\]]*\]\(([^)\s]+)")
CODE_PATH = re.compile(r"`(/[^`\s]+)`")


class _Links(HTMLParser):
    def __init__(self) -> None:
        super().__init__()
        self.links: list[str] = []

    def handle_starttag(self, tag: str, attrs: list[tuple[str, str | None]]) -> None:
        for name, value in attrs:
            if name in ("src", "href") and value:
                self.links.append(value)


def _broken_links(site: Path) -> list[str]:
    broken = []
    for page in site.rglob("*.html"):
        parser = _Links()
        parser.feed(page.read_text(encoding="utf-8"))
        for link in parser.links:
            parts = urlsplit(link)
            if parts.scheme or parts.netloc or not parts.path:
                continue  # another site, a mail address or an anchor on the same page
            path = unquote(parts.path)
            target = (site / path.lstrip("/")) if path.startswith("/") else page.parent / path
            if not (target.exists() or (target / "index.html").exists()):
                broken.append(f"{page.relative_to(site)}: {link}")
    return broken


@pytest.mark.slow
def test_site_builds_strict_with_every_link_and_image_resolving(tmp_path):
    mkdocs = shutil.which("mkdocs", path=str(Path(sys.executable).parent)) or "mkdocs"
    site = tmp_path / "site"
    env = {**os.environ, "NO_MKDOCS_2_WARNING": "1"}
    run = subprocess.run(
        [mkdocs, "build", "--strict", "-d", str(site)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr[-3000:]
    assert "WARNING" not in run.stderr, run.stderr[-3000:]
    assert (site / "findings" / "accuracy-costs" / "index.html").exists()
    assert _broken_links(site) == []


def test_broken_link_finder_sees_a_missing_image(tmp_path):
    (tmp_path / "page").mkdir()
    (tmp_path / "page" / "index.html").write_text(
        '<img src="../fig.png"><a href="../other/">x</a><a href="https://x.org/y">y</a>'
    )
    (tmp_path / "other").mkdir()
    (tmp_path / "other" / "index.html").write_text("")
    assert _broken_links(tmp_path) == ["page/index.html: ../fig.png"]


def _committed_text_files() -> list[Path]:
    listed = subprocess.run(
        ["git", "ls-files", "*.md", "*.yml", "*.toml", "*.cfg", "Makefile"],
        cwd=ROOT,
        capture_output=True,
        text=True,
        check=False,
    )
    if listed.returncode == 0:
        return [ROOT / name for name in listed.stdout.split() if (ROOT / name).is_file()]
    # not a git checkout (a source archive): every such file of the tree but build output
    skipped = {".venv", "site", ".git", "demo-output"}
    patterns = ("*.md", "*.yml", "*.toml", "*.cfg", "Makefile")
    return [
        path
        for pattern in patterns
        for path in ROOT.rglob(pattern)
        if not skipped.intersection(path.relative_to(ROOT).parts)
    ]


def test_no_committed_link_holds_an_absolute_path_of_the_writing_machine():
    found = []
    for path in _committed_text_files():
        text = path.read_text(encoding="utf-8", errors="replace")
        for number, line in enumerate(text.splitlines(), 1):
            targets = MARKDOWN_LINK.findall(line) + CODE_PATH.findall(line)
            for target in targets:
                if target.startswith(MACHINE_ROOTS):
                    found.append(f"{path.relative_to(ROOT)}:{number}: {target}")
    assert found == []


def test_bench_block_of_a_nested_output_links_through_the_docs_link(tmp_path):
    """`make bench -o benchmarks/cost --page docs/...`: figures via docs/benchmarks/cost/."""
    repo = tmp_path / "repo"
    output = repo / "benchmarks" / "cost"
    output.mkdir(parents=True)
    (repo / "pyproject.toml").write_text("")
    (repo / "docs" / "findings").mkdir(parents=True)
    (repo / "docs" / "benchmarks").symlink_to("../benchmarks")
    page = repo / "docs" / "findings" / "page.md"
    page.write_text("<!-- bench:start -->\n<!-- bench:end -->\n")
    figure = output / "denoc_cost.png"
    figure.write_bytes(b"")

    class _Result:
        title, headline, figures = "DeNOC", "ratio", [figure]

    env = {
        "date": "d",
        "cpu": "c",
        "pinocchio": "p",
        "numpy": "n",
        "scipy": "s",
        "blas_threads": {"threads_all": 2, "n": 100, "ratio": 1.0},
    }
    update_readme(page, env, [_Result()], output)  # an absolute output, as a script gives
    text = page.read_text()
    assert "](../benchmarks/cost/denoc_cost.png)" in text
    assert "Full report: `benchmarks/cost/report.md`" in text
    assert str(tmp_path) not in text


def test_readme_command_table_lists_every_command():
    from gimwatch.cli import COMMANDS

    rows = [
        line
        for line in (ROOT / "README.md").read_text().splitlines()
        if line.startswith("| `gimwatch ")
    ]
    named = {word for row in rows for word in re.findall(r"`gimwatch (\w+)", row)}
    assert set(COMMANDS) - named == set()
