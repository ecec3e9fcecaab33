"""Section ``explain``: what a conditioning map costs, dense (7-DoF arm) and O(n) (long chain).

Each case is one `gimwatch.explain.maps.conditioning_map` of κ and δ, timed whole (wall
clock, robot loading included, worker start-up included when ``workers`` > 1), once: a map is
a one-shot job, and its first run is what a user waits for.

* ``panda`` (7 arm joints + 2 fingers, nv = 9), joints 2 × 4, 200 × 200, dense path (CRBA +
  a batched eigen-solve per chunk), in this process and on 2 worker processes;
* ``chain:1000``, joints 1 × 500, 100 × 100, O(n) path (DeNOC's linear-time state for δ, the
  κ tracker for κ, serpentine rows), on 2 worker processes.

Quick runs take 20 × 20 and ``chain:100`` at 10 × 10, in this process.
"""

from __future__ import annotations

import time

from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.report import markdown_table
from gimwatch.explain.maps import conditioning_map

__all__ = ["CASES", "COLUMNS", "run"]

#: (robot, (x joint, y joint), grid, quick grid, path, workers)
CASES = (
    ("panda", ("panda_joint2", "panda_joint4"), 200, 20, "crba", 1),
    ("panda", ("panda_joint2", "panda_joint4"), 200, 20, "crba", 2),
    ("chain:1000", ("joint_0001", "joint_0500"), 100, 10, "denoc", 2),
)
COLUMNS = ("robot", "nv", "path", "grid", "points", "workers", "seconds", "us_per_point")


def measure(context: BenchContext) -> Table:
    """One row per case of `CASES`."""
    table = Table("explain", COLUMNS)
    for spec, joints, grid, quick_grid, path, workers in CASES:
        if context.quick:  # a smoke run: in this process, no worker start-up
            grid, workers = quick_grid, 1
            spec = spec.replace("1000", "100").replace("0500", "050").replace("0001", "001")
            x, y = (j.replace("0500", "050").replace("0001", "001") for j in joints)
            joints = (x, y)
        context.progress(f"  {spec}: {grid} x {grid} on the {path} path, {workers} worker(s)")
        start = time.perf_counter()
        result = conditioning_map(
            spec,
            joints,
            grid=grid,
            backend=path,
            workers=workers,
            metrics=["kappa", "diagonal_ratio"],
        )
        seconds = time.perf_counter() - start
        nv = len(result.base_q)
        table.add(
            robot=result.robot,
            nv=nv,
            path=path,
            grid=grid,
            points=grid * grid,
            workers=workers,
            seconds=seconds,
            us_per_point=1e6 * seconds / (grid * grid),
        )
    return table


def run(context: BenchContext) -> SectionResult:
    """Time the maps and summarise."""
    with threadpool_limits(limits=1, user_api="blas"):
        table = measure(context)
    columns = {
        "robot": "robot",
        "nv": "nv",
        "path": "path",
        "grid": "grid",
        "workers": "workers",
        "seconds": "wall time (s)",
        "us_per_point": "µs / point",
    }
    arm = min(r["seconds"] for r in table.rows if r["path"] == "crba")
    chain = next(r["seconds"] for r in table.rows if r["path"] == "denoc")
    verdict = (
        f"A {table.rows[0]['grid']}² map of κ and δ of the 7-DoF arm takes {arm:.1f} s at best; "
        f"a {table.rows[-1]['grid']}² map of the {table.rows[-1]['nv']}-link chain on the O(n) "
        f"path takes {chain:.0f} s."
    )
    text = [
        "Wall time of one `conditioning_map` of κ and δ (robot loading and worker start-up "
        "included), one run per case.",
        "",
        markdown_table(table.rows, columns),
        "",
        verdict,
    ]
    return SectionResult(
        name="explain",
        title="Conditioning maps",
        tables=[table],
        markdown="\n".join(text),
        headline="\n".join([markdown_table(table.rows, columns), "", verdict]),
        summary={"arm_map_s": arm, "chain_map_s": chain},
    )
