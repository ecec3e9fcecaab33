"""Every ```python and ```sh block in README.md and docs/**/*.md runs, from an empty folder.

The python blocks of one page run in order in one namespace (a page reads as one session).
Every line of an ``sh`` block is a command run in a fresh empty folder with the installed
``gimwatch`` (exit 0 expected); a ``text`` block whose lines start with ``$ `` is a console
transcript: its commands are run and their output must be the one shown. A block may be kept
from running only with a stated reason, on the line just above its fence, and the reason is
reported as the skip reason (``pytest -ra``)::

    <!-- no-run: needs a MuJoCo licence server -->

An ``sh`` block with a command other than ``gimwatch`` (``pip``, ``make``) must carry one.
Command synopses (``gimwatch analyze ROBOT [--q Q...]``) are ``text`` blocks. Other fences
(``toml``, plain ``text``) are shown, not run. The pages are found by walking ``docs/``
without following its links to ``benchmarks/`` (reports, not pages) and ``notebooks/`` (run
by ``pytest --nbmake``), plus the notebooks' README, which is a page.
"""

from __future__ import annotations

import os
import re
import shlex
import subprocess
import sys
from dataclasses import dataclass
from pathlib import Path

import matplotlib
import pytest

ROOT = Path(__file__).resolve().parents[1]
SHELL_FENCES = ("sh", "bash", "shell")
FENCE = re.compile(r"^```(\S*)[^\n]*\n(.*?)^```\s*$", re.DOTALL | re.MULTILINE)
NO_RUN = re.compile(r"<!--\s*no-run:\s*(.*?)\s*-->\s*$")


@dataclass(frozen=True)
class Block:
    page: Path
    line: int
    code: str
    skip_reason: str | None


def doc_pages() -> list[Path]:
    pages = [ROOT / "README.md", ROOT / "notebooks" / "README.md"]
    for folder, dirs, files in os.walk(ROOT / "docs"):  # links to folders are not followed
        dirs[:] = sorted(d for d in dirs if not (Path(folder) / d).is_symlink())
        pages += [Path(folder) / f for f in sorted(files) if f.endswith(".md")]
    return pages


def python_blocks(page: Path) -> list[Block]:
    return fenced_blocks(page, ("python", "py"))


def fenced_blocks(page: Path, languages: tuple[str, ...]) -> list[Block]:
    text = page.read_text(encoding="utf-8")
    blocks = []
    for match in FENCE.finditer(text):
        if match.group(1) not in languages:
            continue
        before = text[: match.start()].rstrip("\n").rsplit("\n", 1)[-1]
        marker = NO_RUN.search(before)
        line = text.count("\n", 0, match.start()) + 1
        blocks.append(Block(page, line, match.group(2), marker.group(1) if marker else None))
    return blocks


PAGES = [page for page in doc_pages() if python_blocks(page)]


def test_pages_are_found():
    names = {page.relative_to(ROOT).as_posix() for page in doc_pages()}
    assert {"README.md", "docs/index.md", "docs/getting-started.md"} <= names, names
    assert not any(name.startswith(("docs/benchmarks/", "docs/notebooks/")) for name in names)
    assert {p.relative_to(ROOT).as_posix() for p in PAGES} >= {
        "README.md",
        "docs/getting-started.md",
    }


def test_fence_parser_reads_markers(tmp_path):
    page = tmp_path / "page.md"
    page.write_text(
        "text\n```python\nx = 1\n```\n\n<!-- no-run: needs a robot arm -->\n```python\nboom\n```\n"
        "```sh\nls\n```\n"
    )
    blocks = python_blocks(page)
    assert [(b.line, b.code, b.skip_reason) for b in blocks] == [
        (2, "x = 1\n", None),
        (7, "boom\n", "needs a robot arm"),
    ]


@pytest.mark.parametrize("page", PAGES, ids=lambda p: p.relative_to(ROOT).as_posix())
def test_python_blocks_run(page, tmp_path, monkeypatch):
    matplotlib.use("Agg")  # a block that plots must not open a window
    if any(".to_dataframe(" in b.code for b in python_blocks(page) if b.skip_reason is None):
        pytest.importorskip("pandas", reason=f"{page.name} calls to_dataframe(): pandas extra")
    monkeypatch.chdir(tmp_path)  # "runnable from any directory"
    namespace: dict = {"__name__": "__docs__"}
    ran = 0
    for block in python_blocks(page):
        if block.skip_reason is not None:
            assert block.skip_reason, f"{page}:{block.line}: no-run needs a reason"
            continue
        code = compile(block.code, f"{page.relative_to(ROOT)}:{block.line}", "exec")
        exec(code, namespace)
        ran += 1
    assert ran, f"{page}: every python block is marked no-run"


@pytest.mark.parametrize("path", sorted((ROOT / "notebooks").glob("*.ipynb")), ids=lambda p: p.name)
def test_notebooks_are_stored_with_their_outputs(path):
    """The docs render notebooks as stored (no execution at build time): outputs must be there."""
    import json

    cells = [c for c in json.loads(path.read_text())["cells"] if c["cell_type"] == "code"]
    assert cells and all(c["execution_count"] is not None for c in cells), "run and save it"
    outputs = [o for c in cells for o in c["outputs"]]
    assert outputs and not [o for o in outputs if o["output_type"] == "error"]
    source = "".join("".join(c["source"]) for c in cells)
    if "plt." in source:  # a figure is an image, not "<Figure size ...>" text (no Agg)
        assert any("image/png" in o.get("data", {}) for o in outputs), path.name
    assert 'matplotlib.use("Agg")' not in source


def test_stated_times_are_the_measured_ones():
    """Times on the front pages come from benchmarks/startup/ and newcomer/times.json."""
    import csv
    import json

    with (ROOT / "benchmarks" / "startup" / "startup.csv").open(newline="") as handle:
        startup = {row["case"]: float(row["median_s"]) for row in csv.DictReader(handle)}
    newcomer = json.loads((ROOT / "benchmarks" / "newcomer" / "times.json").read_text())

    def flat(page: str) -> str:
        return " ".join((ROOT / page).read_text(encoding="utf-8").split())

    started = flat("docs/getting-started.md")
    ratio = startup["gimwatch analyze ur5"] / startup["bare ur5 (pinocchio crba + eigvalsh)"]
    for text in (
        f"`import gimwatch` takes {startup['import gimwatch']:.2f} s against "
        f"{startup['import pinocchio']:.2f} s",
        f"Pinocchio and SciPy: {startup['import gimwatch + first names']:.2f} s",
        f"`gimwatch analyze ur5` takes {startup['gimwatch analyze ur5']:.2f} s, {ratio:.2f}x",
        f"`gimwatch demo` takes {startup['gimwatch demo']:.1f} s",
    ):
        assert text in started, text
    assert f"({startup['gimwatch demo']:.1f} s on a 2-core machine" in flat(
        "docs/guide/simulate.md"
    )
    readme = flat("README.md")
    for text in (
        f"`pip install .` {newcomer['pip_install_s']:.0f} s",
        f"the Python above {newcomer['readme_python_snippet_s']:.1f} s",
        # one source per figure: command times from benchmarks/startup/ only
        f"`gimwatch analyze ur5` {startup['gimwatch analyze ur5']:.2f} s",
        f"`gimwatch simulate chain_10` {startup['gimwatch simulate chain_10']:.1f} s",
        f"`gimwatch demo` {startup['gimwatch demo']:.1f} s",
        f"{newcomer['readme_watch_loop_first_run_s']:.1f} s for the block above, "
        f"{newcomer['readme_watch_loop_second_run_s']:.1f} s on later runs",
    ):
        assert text in readme, text
    assert (
        f"{newcomer['readme_watch_loop_first_run_s']:.1f} s on its first run in a fresh install, "
        f"{newcomer['readme_watch_loop_second_run_s']:.1f} s after" in started
    )
    assert newcomer["install_analysis_and_simulation_s"] < 120  # "under 2 minutes"
    for page in ("README.md", "docs/getting-started.md"):  # not quoted from the second source
        text = flat(page)
        for key in ("analyze_ur5_s", "simulate_chain_10_s", "demo_s"):
            assert f"{newcomer[key]:.2f} s" not in text and f" {newcomer[key]:.1f} s" not in text


def shell_commands(code: str) -> list[str]:
    """The commands of an ``sh`` block: one a line (``\\`` continues), ``# comments`` cut."""
    joined = re.sub(r"\\\n", " ", code)
    commands = []
    for line in joined.splitlines():
        words = shlex.split(line, comments=True)
        if words:
            commands.append(shlex.join(words))
    return commands


def console_steps(code: str) -> list[tuple[str, str]]:
    """(command, expected output) pairs of a console transcript (``$ cmd`` then its output)."""
    steps: list[tuple[str, list[str]]] = []
    for line in code.splitlines():
        if line.startswith("$ "):
            steps.append((line[2:], []))
        elif steps:
            steps[-1][1].append(line)
    return [(command, "\n".join(lines).strip("\n")) for command, lines in steps]


def run_gimwatch(command: str, cwd: Path) -> subprocess.CompletedProcess:
    """Run one documented ``gimwatch ...`` command as written, with this tree's gimwatch."""
    words = shlex.split(command)
    assert words[0] == "gimwatch", f"{command!r}: only gimwatch commands run here"
    environment = {**os.environ, "PYTHONPATH": str(ROOT), "MPLBACKEND": "Agg"}
    return subprocess.run(
        [sys.executable, "-m", "gimwatch", *words[1:]],
        cwd=cwd,
        env=environment,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
    )


SHELL_BLOCKS = [b for page in doc_pages() for b in fenced_blocks(page, SHELL_FENCES)]
CONSOLE_BLOCKS = [
    b
    for page in doc_pages()
    for b in fenced_blocks(page, ("text", "console"))
    if b.code.startswith("$ ")
]


def _block_id(block: Block) -> str:
    return f"{block.page.relative_to(ROOT).as_posix()}:{block.line}"


def test_shell_parsers():
    assert shell_commands("gimwatch a x  # note\n\n# alone\ngimwatch b \\\n  --json\n") == [
        "gimwatch a x",
        "gimwatch b --json",
    ]
    assert console_steps("$ gimwatch a\nline 1\nline 2\n$ gimwatch b\n") == [
        ("gimwatch a", "line 1\nline 2"),
        ("gimwatch b", ""),
    ]
    assert len(SHELL_BLOCKS) >= 5 and len(CONSOLE_BLOCKS) >= 3


@pytest.mark.parametrize("block", SHELL_BLOCKS, ids=_block_id)
def test_shell_blocks_run(block, tmp_path):
    commands = shell_commands(block.code)
    assert commands, f"{_block_id(block)}: an empty sh block"
    if block.skip_reason is not None:
        assert block.skip_reason.strip(), f"{_block_id(block)}: no-run needs a reason"
        pytest.skip(f"{_block_id(block)}: {block.skip_reason}")
    for command in commands:
        assert command.startswith("gimwatch "), (
            f"{_block_id(block)}: {command!r} is not a gimwatch command; mark the block "
            "<!-- no-run: reason --> or make it a text block"
        )
        done = run_gimwatch(command, tmp_path)
        assert done.returncode == 0, f"{_block_id(block)}: {command}: {done.stderr[-2000:]}"


@pytest.mark.parametrize("block", CONSOLE_BLOCKS, ids=_block_id)
def test_console_transcripts_match(block, tmp_path):
    if block.skip_reason is not None:
        assert block.skip_reason.strip(), f"{_block_id(block)}: no-run needs a reason"
        pytest.skip(f"{_block_id(block)}: {block.skip_reason}")
    for command, expected in console_steps(block.code):
        done = run_gimwatch(command, tmp_path)
        shown = (done.stdout + done.stderr).strip("\n")
        assert shown == expected, f"{_block_id(block)}: {command}"


@pytest.mark.parametrize(
    ("measured", "command"),
    [
        ("benchmarks/startup/summary.json", "gimwatch bench startup -o benchmarks/startup"),
        ("benchmarks/newcomer/times.json", "bash benchmarks/newcomer/measure.sh"),
    ],
)
def test_measured_times_are_not_older_than_the_code_they_time(measured, command):
    """A timing file records the modules its commands imported (gimwatch.bench.freshness)."""
    import json

    from gimwatch.bench.freshness import FINGERPRINT_KEY, stale_modules

    record = json.loads((ROOT / measured).read_text())
    if "sections" in record:
        record = record["sections"]["startup"]
    fingerprint = record[FINGERPRINT_KEY]
    assert {"gimwatch/cli/analyze.py", "gimwatch/model/robots.py"} <= set(fingerprint["modules"])
    stale = stale_modules(fingerprint, ROOT)
    assert not stale, f"{measured} predates changes to {stale}: regenerate it with `{command}`"
