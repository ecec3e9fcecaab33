"""Section ``startup``: how long a first contact with gimwatch takes, in fresh processes.

Every row is the wall time of a fresh Python process, measured from the parent around
``subprocess.run`` (interpreter start, imports, work, exit), repeated with the cases
interleaved so that a busy moment on the machine hits them alike; medians are reported.

* ``import pinocchio`` against ``import gimwatch`` (which imports nothing until a name is
  used) and ``import gimwatch`` followed by the names a first script touches;
* a bare script that loads ur5 with Pinocchio from example-robot-data's URDF and runs CRBA +
  ``numpy.linalg.eigvalsh``, against ``gimwatch analyze ur5`` doing that and more (URDF checks,
  pivots, the table);
* ``gimwatch --help``;
* once, outside the repeats, ``gimwatch demo`` (the main job, without the GIF) and
  ``gimwatch simulate`` of the 10-link chain scene with κ and δ watched.

The section's summary records which gimwatch modules the measured processes import and a
digest of each (`gimwatch.bench.freshness`): ``tests/test_docs.py`` fails when the code
changed since, so the times quoted in the docs are never older than the code.

Targets: ``import gimwatch`` at most 0.3 s more than ``import pinocchio``; ``gimwatch analyze
ur5`` at most 1.5x the bare script; ``gimwatch demo`` at most 30 s.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.freshness import FINGERPRINT_KEY, fingerprint, modules_imported_by
from gimwatch.bench.report import markdown_table

__all__ = ["BARE_UR5", "CASES", "COLUMNS", "run"]

#: The reference for ``gimwatch analyze ur5``: Pinocchio alone, no checks, no table.
BARE_UR5 = """
import numpy as np
import pinocchio as pin
from example_robot_data.robots_loader import ROBOTS, getModelPath
loader = ROBOTS["ur5"]
relative = f"{loader.path}/{loader.urdf_subpath}/{loader.urdf_filename}"
model = pin.buildModelFromUrdf(f"{getModelPath(relative)}/{relative}")
M = pin.crba(model, model.createData(), pin.neutral(model))
print(np.linalg.eigvalsh(M)[[0, -1]])
"""

#: Case name -> arguments after ``python``; all run in every repeat.
CASES: dict[str, list[str]] = {
    "python": ["-c", "pass"],
    "import pinocchio": ["-c", "import pinocchio"],
    "import gimwatch": ["-c", "import gimwatch"],
    "import gimwatch + first names": [
        "-c",
        "import gimwatch as gw; gw.load_robot, gw.gim, gw.condition_number, gw.run_scene",
    ],
    "bare ur5 (pinocchio crba + eigvalsh)": ["-c", BARE_UR5],
    "gimwatch analyze ur5": ["-m", "gimwatch", "analyze", "ur5"],
    "gimwatch --help": ["-m", "gimwatch", "--help"],
}
COLUMNS = ("case", "repeats", "median_s", "min_s", "max_s")
IMPORT_TARGET_S = 0.3
ANALYZE_TARGET_RATIO = 1.5
DEMO_TARGET_S = 30.0


#: Processes of the same code paths as the "once" cases, for the fingerprint (short runs).
ONCE_PROBES: dict[str, list[str]] = {
    "gimwatch demo": ["-m", "gimwatch", "demo", "--duration", "0.05", "-o", "probe-demo"],
    "gimwatch simulate chain_10": ["-m", "gimwatch", "simulate", "chain_10", "-o", "probe-run"],
}


def measured_code(cases: list[list[str]], cwd: Path) -> dict:
    """The fingerprint of the gimwatch modules that ``cases`` import."""
    return fingerprint(modules_imported_by(cases, cwd))


def _wall(argv: list[str], cwd: Path) -> float:
    start = time.perf_counter()
    done = subprocess.run(
        [sys.executable, *argv], cwd=cwd, capture_output=True, text=True, check=False
    )
    wall = time.perf_counter() - start
    if done.returncode != 0:
        raise RuntimeError(f"{argv[:3]} failed: {done.stderr.strip()[-300:]}")
    return wall


def measure(context: BenchContext) -> tuple[Table, dict[str, float], dict]:
    """Time every case in fresh processes; the table, the medians by case, the fingerprint."""
    repeats = 1 if context.quick else 9
    samples: dict[str, list[float]] = {name: [] for name in CASES}
    with tempfile.TemporaryDirectory() as folder:
        cwd = Path(folder)
        for name in () if context.quick else CASES:  # warm the file cache once, untimed
            _wall(CASES[name], cwd)
        for k in range(repeats):
            context.progress(f"  round {k + 1}/{repeats}")
            for name, argv in CASES.items():
                samples[name].append(_wall(argv, cwd))
        once: dict[str, float] = {}
        if not context.quick:
            context.progress("  gimwatch demo (once)")
            once["gimwatch demo"] = _wall(["-m", "gimwatch", "demo", "-o", "demo"], cwd)
        if not context.quick:
            context.progress("  gimwatch simulate chain_10 (once)")
            once["gimwatch simulate chain_10"] = _wall(
                ["-m", "gimwatch", "simulate", "chain_10", "-o", "run"], cwd
            )
        context.progress("  which modules the cases import (fingerprint)")
        probes = [argv for name, argv in CASES.items() if "gimwatch" in name]
        code = measured_code(probes + [ONCE_PROBES[name] for name in once], cwd)
    table = Table("startup", COLUMNS)
    medians = {}
    for name, values in samples.items():
        medians[name] = statistics.median(values)
        table.add(
            case=name,
            repeats=len(values),
            median_s=medians[name],
            min_s=min(values),
            max_s=max(values),
        )
    for name, value in once.items():
        medians[name] = value
        table.add(case=name, repeats=1, median_s=value, min_s=value, max_s=value)
    return table, medians, code


def _verdict(ok: bool | None) -> str:
    return "—" if ok is None else ("met" if ok else "**not met**")


def _findings(medians: dict[str, float], summary: dict) -> list[str]:
    """One line per figure against its target: import, analyze, demo, simulate."""
    import_extra = summary["import_gimwatch_minus_pinocchio_s"]
    first_extra = summary["import_first_names_minus_pinocchio_s"]
    ratio, demo = summary["analyze_ur5_over_bare"], summary["demo_s"]
    lines = [
        f"- `import gimwatch` costs {import_extra:+.3f} s against `import pinocchio` "
        f"({medians['import gimwatch']:.3f} s vs {medians['import pinocchio']:.3f} s; "
        f"target ≤ +{IMPORT_TARGET_S} s: {_verdict(summary['import_target_met'])}); with the "
        f"first names a script uses (`load_robot`, `gim`, `condition_number`, `run_scene`): "
        f"{first_extra:+.3f} s.",
        f"- `gimwatch analyze ur5` takes {medians['gimwatch analyze ur5']:.3f} s, "
        f"{ratio:.2f}x a bare Pinocchio script loading ur5 and running CRBA + `eigvalsh` "
        f"({medians['bare ur5 (pinocchio crba + eigvalsh)']:.3f} s; target ≤ "
        f"{ANALYZE_TARGET_RATIO}x: {_verdict(summary['analyze_target_met'])}).",
    ]
    if demo is not None:
        lines.append(
            f"- `gimwatch demo` (the paper's 4-, 10- and 20-link chains, 5 s each, figures, "
            f"no GIF) takes {demo:.1f} s (target ≤ {DEMO_TARGET_S:g} s: "
            f"{_verdict(summary['demo_target_met'])})."
        )
    simulate = medians.get("gimwatch simulate chain_10")
    if simulate is not None:
        lines.append(
            f"- `gimwatch simulate chain_10` (5 s of the 10-link chain, DOP853 at "
            f"1e-10, κ and δ watched, results folder with plots) takes {simulate:.1f} s."
        )
    return lines


def run(context: BenchContext) -> SectionResult:
    """Measure and summarise against the targets."""
    table, medians, code = measure(context)
    import_extra = medians["import gimwatch"] - medians["import pinocchio"]
    first_extra = medians["import gimwatch + first names"] - medians["import pinocchio"]
    ratio = medians["gimwatch analyze ur5"] / medians["bare ur5 (pinocchio crba + eigvalsh)"]
    demo = medians.get("gimwatch demo")
    summary = {
        "import_gimwatch_minus_pinocchio_s": import_extra,
        "import_first_names_minus_pinocchio_s": first_extra,
        "analyze_ur5_over_bare": ratio,
        "demo_s": demo,
        "import_target_met": import_extra <= IMPORT_TARGET_S,
        "analyze_target_met": ratio <= ANALYZE_TARGET_RATIO,
        "demo_target_met": None if demo is None else demo <= DEMO_TARGET_S,
        FINGERPRINT_KEY: code,
    }
    headline = "\n".join(_findings(medians, summary))
    columns = {
        "case": "process",
        "repeats": "runs",
        "median_s": "median (s)",
        "min_s": "min (s)",
        "max_s": "max (s)",
    }
    markdown = (
        "Wall time of fresh processes, measured from the parent (interpreter start, imports, "
        "work, exit); the repeated cases run interleaved, medians.\n\n"
        + markdown_table(table.rows, columns)
        + "\n\n"
        + headline
    )
    return SectionResult(
        name="startup",
        title="Startup and first contact",
        tables=[table],
        markdown=markdown,
        headline=headline,
        summary=summary,
        measured_code=code,  # the modules the timed processes imported, not this one's
    )
