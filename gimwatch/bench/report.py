"""Write the benchmark's files: fixed-column CSV/JSON, ``report.md``, ``summary.json``, docs block.

The report is headed by what makes numbers comparable: the versions of gimwatch, Pinocchio,
NumPy, SciPy and mpmath, the date, the CPU model and the BLAS thread settings, plus the
measured cost of multi-threaded BLAS on a 100 x 100 ``eigvalsh`` (the reason benchmarks pin
BLAS to one thread).
"""

from __future__ import annotations

import csv
import datetime
import io
import os
import platform
import re
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

from gimwatch._version import __version__
from gimwatch.bench.freshness import FINGERPRINT_KEY
from gimwatch.bench.records import SectionResult, Table
from gimwatch.bench.timing import blas_thread_ratio, thread_settings
from gimwatch.errors import InputError
from gimwatch.output.atomic import write_json_atomic, write_text_atomic
from gimwatch.output.environment import cpu_model

__all__ = [
    "environment",
    "markdown_table",
    "update_readme",
    "write_report",
    "write_section",
    "write_table",
]

README_START, README_END = "<!-- bench:start -->", "<!-- bench:end -->"


def page_markers(text: str, output: str | Path) -> tuple[str, str]:
    """The markers of the block a run into ``output`` regenerates in a page's ``text``.

    ``<!-- bench:NAME:start -->`` / ``<!-- bench:NAME:end -->`` (NAME the output folder's
    name) when the page has them, so that one page can hold the blocks of several folders;
    else `README_START` / `README_END`.
    """
    name = Path(output).name
    start, end = f"<!-- bench:{name}:start -->", f"<!-- bench:{name}:end -->"
    return (start, end) if start in text and end in text else (README_START, README_END)


def _version(package: str) -> str:
    try:
        return version(package)
    except PackageNotFoundError:
        return "not installed"


def environment(*, quick: bool = False) -> dict:
    """Versions, date, CPU, thread settings and the measured BLAS-threads slowdown."""
    import numpy
    import pinocchio
    import scipy

    return {
        "gimwatch": __version__,
        "pinocchio": pinocchio.__version__,
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "mpmath": _version("mpmath"),
        "python": platform.python_version(),
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "cpu": cpu_model(),
        "threads": thread_settings(),
        "blas_threads": blas_thread_ratio(100, quick=quick),
        "quick": quick,
    }


def _csv_text(table: Table) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=list(table.columns), lineterminator="\n")
    writer.writeheader()
    for row in table.rows:
        writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})
    return buffer.getvalue()


def write_table(output: Path, table: Table, measured_code: dict | None = None) -> tuple[Path, Path]:
    """Write ``<name>.csv`` and ``<name>.json`` (``{"columns": [...], "rows": [...]}``).

    ``measured_code`` (a `gimwatch.bench.freshness.fingerprint`) goes into the JSON under
    ``measured_code``: a test then tells when the table is older than the code it measured.
    """
    csv_path = write_text_atomic(output / f"{table.name}.csv", _csv_text(table))
    record: dict = {"columns": list(table.columns), "rows": table.rows}
    if measured_code:
        record[FINGERPRINT_KEY] = measured_code
    json_path = write_json_atomic(output / f"{table.name}.json", record)
    return csv_path, json_path


def write_section(output: Path, result: SectionResult) -> None:
    """Write a finished section's tables (its figures are written by the section itself)."""
    for table in result.tables:
        write_table(output, table, result.measured_code)


def _header(env: dict) -> list[str]:
    blas = env["blas_threads"]
    lines = [
        f"gimwatch {env['gimwatch']} · Pinocchio {env['pinocchio']} · NumPy {env['numpy']} · "
        f"SciPy {env['scipy']} · mpmath {env['mpmath']} · Python {env['python']}",
        "",
        f"- date: {env['date']}",
        f"- CPU: {env['cpu']}",
        f"- thread settings during the run: {env['threads']} (BLAS pinned to one thread)",
        f"- why: a {blas['n']}x{blas['n']} `eigvalsh` takes {blas['one_thread_s'] * 1e3:.3g} ms "
        f"on one BLAS thread and {blas['all_threads_s'] * 1e3:.3g} ms on {blas['threads_all']} "
        f"({blas['ratio']:.3g}x) in this run",
        "- method: warm-up calls, then 7 timed rounds (each at least 20 ms of repeated calls);"
        " medians per call; every ratio between medians of this run",
    ]
    if env.get("quick"):
        lines.append("- **quick run**: tiny sizes for a smoke test; the numbers mean nothing")
    return lines


def write_report(
    output: Path,
    env: dict,
    results: list[SectionResult],
    skipped: dict[str, str],
    *,
    quick: bool = False,
) -> Path:
    """Write ``report.md`` and ``summary.json`` for the sections that finished."""
    lines = ["# gimwatch bench: what accuracy costs in time", "", *_header(env), ""]
    for result in results:
        lines += [f"## {result.title}", "", result.markdown.strip(), ""]
        lines += [f"![{f.stem}]({f.name})" for f in result.figures] + [""]
    if skipped:
        lines += ["## Not run", ""]
        lines += [f"- `{name}`: {reason}" for name, reason in skipped.items()] + [""]
    summary = {
        "environment": env,
        "sections": {r.name: r.summary for r in results},
        "skipped": skipped,
    }
    write_json_atomic(output / "summary.json", summary)
    return write_text_atomic(output / "report.md", "\n".join(lines).rstrip() + "\n")


def update_readme(readme: Path, env: dict, results: list[SectionResult], output: Path) -> Path:
    """Replace the block between the bench markers in a Markdown page with the headlines.

    The markers are those of `page_markers`: a folder's own block when the page has one.

    The page is a docs page (``docs/findings/accuracy-costs.md``) or a README. Figures are
    linked by a path relative to the page; from a docs page they go through the folder's link
    in ``docs/`` (``docs/benchmarks`` → ``benchmarks``) when there is one, so that MkDocs
    publishes them.

    Raises:
        InputError: The page lacks the ``<!-- bench:start -->``/``<!-- bench:end -->`` markers.
    """
    text = readme.read_text(encoding="utf-8")
    start, end = page_markers(text, output)
    pattern = re.compile(re.escape(start) + r".*?" + re.escape(end), re.DOTALL)
    if not pattern.search(text):
        raise InputError(f"{readme}", f"a file with {start} and {end} markers", "no markers")
    prefix = _figure_prefix(readme, output)
    blas = env["blas_threads"]
    body = [
        start,
        f"Measured by `make bench` ({env['date']}; {env['cpu']}; Pinocchio {env['pinocchio']}, "
        f"NumPy {env['numpy']}, SciPy {env['scipy']}; BLAS on one thread — on "
        f"{blas['threads_all']} threads a {blas['n']}x{blas['n']} `eigvalsh` was "
        f"{blas['ratio']:.3g}x slower in the same run). Full report: "
        f"`{_repository_path(output)}/report.md`.",
        "",
    ]
    for result in results:
        if not result.headline.strip() and not result.figures:
            continue  # no empty headings
        body += [f"## {result.title}", "", result.headline.strip(), ""]
        body += [f"![{f.stem}]({prefix}{f.name})" for f in result.figures[:1]] + [""]
    body.append(end)
    new = pattern.sub(lambda _: "\n".join(body), text)
    return write_text_atomic(readme, new)


def _figure_prefix(page: Path, output: Path) -> str:
    """The relative path from ``page`` to ``output`` ("../benchmarks/"), through a link if any.

    The nearest folder above the page holding an entry named like ``output`` or one of its
    parents that resolves to it (a symbolic link ``docs/benchmarks`` for ``benchmarks/cost``,
    or ``output`` itself) is used; otherwise the plain relative path. Never an absolute path:
    the page is read on other machines.
    """
    target = Path(output).resolve()
    page_dir = Path(page).absolute().parent
    for ancestor in (target, *target.parents):
        if not ancestor.name:
            break  # the file-system root: no link to it
        rest = target.relative_to(ancestor)
        for folder in (page_dir, *page_dir.parents):
            candidate = folder / ancestor.name
            if candidate.exists() and candidate.resolve() == ancestor:
                link = Path(os.path.relpath(candidate, page_dir)) / rest
                return link.as_posix() + "/"
    return Path(os.path.relpath(target, page_dir.resolve())).as_posix() + "/"


def _repository_path(output: Path) -> str:
    """``output`` relative to the repository holding it ("benchmarks/cost"), else its name."""
    target = Path(output).resolve()
    for folder in target.parents:
        if (folder / "pyproject.toml").exists():
            return target.relative_to(folder).as_posix()
    return target.name


def markdown_table(rows: list[dict], columns: dict[str, str]) -> str:
    """A Markdown table of ``rows``; ``columns`` maps a row key to its header.

    Floats are printed with 3 significant digits (4 for values near 1), None as "—".
    """

    def cell(value: object) -> str:
        if value is None:
            return "—"
        if isinstance(value, float):
            return f"{value:.3g}"
        return str(value)

    lines = [
        "| " + " | ".join(columns.values()) + " |",
        "|" + "---|" * len(columns),
    ]
    lines += ["| " + " | ".join(cell(row.get(k)) for k in columns) + " |" for row in rows]
    return "\n".join(lines)
