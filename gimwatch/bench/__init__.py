"""What accuracy costs in time: the sections of ``gimwatch bench`` and the run that ties them.

Each section is a module of this package with ``run(context) -> SectionResult``; the
`SECTIONS` registry names them, with the optional packages each one needs. A section whose
optional package is not installed (MuJoCo for the MuJoCo loops) is reported as skipped by
``all`` and refused when asked for by name.

Every section writes fixed-column CSV/JSON tables and PNG plots into the output folder's
staging copy as soon as it finishes; ``report.md`` is then written from the sections that
finished, headed by versions, date, CPU and thread settings, and the folder is swapped into
place (`gimwatch.output.folders`), even when the run was interrupted: it keeps what it
measured. Files of the previous folder that this run does not rewrite are kept (other
sections' tables, the folder's README).
"""

from __future__ import annotations

import importlib
import importlib.util
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

from gimwatch.bench.records import BenchContext, SectionResult, Table
from gimwatch.errors import InputError
from gimwatch.output.folders import ResultsFolder

__all__ = [
    "SECTIONS",
    "BenchContext",
    "Section",
    "SectionResult",
    "Table",
    "run_bench",
    "section_status",
]


@dataclass(frozen=True)
class Section:
    """A registered section: its name, heading, the module that runs it, what it needs.

    ``requires`` names the optional packages (import names) the section cannot run without;
    a section that only adds a peer when one is installed (``integrators``) requires none.
    """

    name: str
    title: str
    module: str
    requires: tuple[str, ...] = ()


#: The sections in report order; ``all`` runs those whose status is None.
SECTIONS: dict[str, Section] = {
    s.name: s
    for s in (
        Section("startup", "Startup and first contact", "gimwatch.bench.startup"),
        Section("conditioning", "Conditioning cost vs n", "gimwatch.bench.conditioning_cost"),
        Section("estimators", "Estimator quality vs cost", "gimwatch.bench.estimators"),
        Section("accuracy", "Forward-dynamics accuracy vs κ", "gimwatch.bench.accuracy"),
        Section("digits", "Digits lost per solver, and their predictor", "gimwatch.bench.digits"),
        Section(
            "dynamics",
            "Dynamics backends per step",
            "gimwatch.bench.dynamics",
        ),
        Section(
            "integrators",
            "Work-precision of integrators (MuJoCo peer)",
            "gimwatch.bench.integrators",
        ),
        Section(
            "watch",
            "Cost of the watch per step",
            "gimwatch.bench.watch_section",
        ),
        Section(
            "watch_mujoco",
            "Cost of the watch in a MuJoCo loop",
            "gimwatch.bench.watch_mujoco",
            requires=("mujoco",),
        ),
        Section(
            "watch_overhead",
            "The watch sample against the bare computation",
            "gimwatch.bench.watch_overhead",
            requires=("mujoco",),
        ),
        Section("denoc", "DeNOC vs Pinocchio cost", "gimwatch.bench.denoc_section"),
        Section("explain", "Conditioning maps", "gimwatch.bench.explain_maps"),
        Section("longchain", "Very long chains on the O(n) path", "gimwatch.bench.longchain_cost"),
        Section("lean", "δ at the cost of its arithmetic", "gimwatch.bench.lean_cost"),
        Section(
            "tracker",
            "κ tracked at O(n) per sample",
            "gimwatch.bench.tracker_cost",
        ),
        Section(
            "tighten",
            "Tightening the tolerance on alarm",
            "gimwatch.bench.tighten",
        ),
    )
}


def _installed(package: str) -> bool:
    # find_spec locates the package without importing it (MuJoCo's import takes a second)
    try:
        return importlib.util.find_spec(package) is not None
    except (ImportError, ValueError):
        return False


def section_status(name: str) -> str | None:
    """None when section ``name`` can run, else why not (one line)."""
    missing = [package for package in SECTIONS[name].requires if not _installed(package)]
    if missing:
        return f"not available: needs {', '.join(missing)} (pip install 'gimwatch[peers]')"
    return None


def run_bench(
    which: Sequence[str],
    output: str | Path,
    *,
    quick: bool = False,
    progress: Callable[[str], None] = lambda line: None,
    readme: str | Path | None = None,
    seed: int = 0,
) -> Path:
    """Run the named sections (or ``["all"]``), write tables, plots and ``report.md``.

    Args:
        which: Section names, or ``["all"]`` for every available section.
        output: Output folder (created).
        quick: Tiny sizes for a smoke run.
        progress: Receives progress lines.
        readme: A README whose "What accuracy costs" block (between the
            ``<!-- bench:start -->`` and ``<!-- bench:end -->`` markers) is regenerated.
        seed: Seed of every random draw.

    Returns:
        The path of ``report.md``.

    Raises:
        InputError: An unknown section, or one whose module cannot be imported.
    """
    # SciPy's own OpenBLAS (the LAPACK numba's eigvalsh calls, in the watch's κ kernel) is
    # loaded now, so that the sections' threadpool_limits(1) pins it too: a library loaded
    # inside such a block keeps all its threads (2 here: a 35 x 35 solve 1.3x slower).
    import scipy.linalg.cython_lapack  # noqa: F401

    from gimwatch.bench.freshness import fingerprint, loaded_modules
    from gimwatch.bench.report import environment, update_readme, write_report, write_section

    names = list(which)
    skipped: dict[str, str] = {}
    if names == ["all"]:
        names = []
        for name in SECTIONS:
            reason = section_status(name)
            if reason:
                skipped[name] = reason
            else:
                names.append(name)
    for name in names:
        if name not in SECTIONS:
            raise InputError("the bench section", f"one of {[*SECTIONS, 'all']}", name)
        reason = section_status(name)
        if reason:
            raise InputError(f"bench section {name!r}", "available", reason)
    with ResultsFolder(output, writer="bench", keep_previous=True) as folder:
        staging = folder.staging
        assert staging is not None  # set on entering the folder
        context = BenchContext(output=staging, quick=quick, progress=progress, seed=seed)
        progress("measuring the environment (BLAS threads)")
        env = environment(quick=quick)
        results: list[SectionResult] = []
        try:
            for name in names:
                progress(f"section {name}")
                module = importlib.import_module(SECTIONS[name].module)
                result = module.run(context)
                if not result.measured_code:  # what this process ran to measure it
                    result.measured_code = fingerprint(loaded_modules())
                write_section(staging, result)
                results.append(result)
        finally:  # an interrupted run still reports (and keeps) the sections it finished
            write_report(staging, env, results, skipped, quick=quick)
            output = folder.commit()
    if readme is not None:
        update_readme(Path(readme), env, results, output)
    return output / "report.md"
