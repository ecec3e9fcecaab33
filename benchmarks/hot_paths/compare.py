"""Hot paths of gimwatch, timed on two commits in one run: is the new house any slower?

Each case runs in its own Python process (three calls outside the clock: numba compiles),
old and new interleaved in alternating order, ``--rounds`` times; the ratio is
median(new) / median(old) of the per-operation CPU times (`time.process_time`: time a
neighbour on a shared machine takes is not counted; each process's fastest of five blocks).
The cases use only the public API that both commits share:

* ``watch_chain10``: `Watch` sample of κ and δ on ``chain:10`` (the compiled sample path);
* ``watch_ur5_delta``: `Watch` sample of δ alone on ur5 (O(n), DeNOC's lean diagonal);
* ``watch_ur5_kappa_s``: `Watch` sample of κ_S on ur5 (the checked `GimState` path);
* ``tracker_chain200``: `track_kappa` along a smooth path of ``chain:200``, 300 samples
  (DeNOC lean, warm-started);
* ``denoc_fd_chain100``: DeNOC's O(n) forward dynamics on ``chain:100``;
* ``analyze_ur5``: ``analyze('ur5')`` (dense: CRBA, eigen-solve, pivots; the robot loaded once);
* ``analyze_chain2000``: ``analyze('chain:2000')`` (the O(n) path: Lanczos on DeNOC).

Usage (from the repository root; writes benchmarks/hot_paths/before_after.csv)::

    python benchmarks/hot_paths/compare.py --old 33517d3 [--new WORKTREE] [--rounds 5]
"""

from __future__ import annotations

import argparse
import csv
import os
import statistics
import subprocess
import sys
import tarfile
import tempfile
from io import BytesIO
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: name -> (setup, one operation, operations per timed block: a block lasts 0.05–0.3 s)
CASES = {
    "watch_chain10": (
        "import numpy as np, gimwatch as g\n"
        "r = g.load_robot('chain:10'); w = g.Watch(r, ('kappa', 'diagonal_ratio'))\n"
        "qs = np.random.default_rng(0).uniform(-3, 3, (N, r.nq)); i = iter(range(10**9))\n",
        "w.sample(0.0, qs[next(i) % N])",
        4000,
    ),
    "watch_ur5_delta": (
        "import numpy as np, gimwatch as g\n"
        "r = g.load_robot('ur5'); w = g.Watch(r, ('diagonal_ratio',))\n"
        "qs = np.random.default_rng(0).uniform(-3, 3, (N, r.nq)); i = iter(range(10**9))\n",
        "w.sample(0.0, qs[next(i) % N])",
        8000,
    ),
    "watch_ur5_kappa_s": (
        "import numpy as np, gimwatch as g\n"
        "r = g.load_robot('ur5'); w = g.Watch(r, ('kappa_equilibrated',))\n"
        "qs = np.random.default_rng(0).uniform(-3, 3, (N, r.nq)); i = iter(range(10**9))\n",
        "w.sample(0.0, qs[next(i) % N])",
        800,
    ),
    "tracker_chain200": (
        "import numpy as np, gimwatch as g\n"
        "from gimwatch.denoc import DenocModel\n"
        "from gimwatch.model.chains import chain_spec\n"
        "lean = DenocModel.from_chain(chain_spec(200)).lean()\n"
        "t = np.linspace(0, 1, 300)[:, None]; base = np.random.default_rng(0).uniform(-1, 1, 200)\n"
        "qs = np.sin(2 * np.pi * t + base)\n",
        "g.track_kappa(lean, qs)",
        1,
    ),
    "denoc_fd_chain100": (
        "import numpy as np\n"
        "from gimwatch.denoc import DenocModel\n"
        "from gimwatch.model.chains import chain_spec\n"
        "lean = DenocModel.from_chain(chain_spec(100)).lean()\n"
        "rng = np.random.default_rng(0); q, v, tau = rng.uniform(-1, 1, (3, 100))\n",
        "lean.forward_dynamics(q, v, tau)",
        1000,
    ),
    "analyze_ur5": (
        "import gimwatch as g\n",
        "g.analyze('ur5')",
        60,
    ),
    "analyze_chain2000": (
        "import gimwatch as g\n",
        "g.analyze('chain:2000')",
        1,
    ),
}

_TIMER = """
import os, time
os.environ.setdefault('OMP_NUM_THREADS', '1')
N = {n}
{setup}
for _ in range(3):  # compiles, and takes the watch past its first, checked sample
    {op}
best = float("inf")
for _ in range(5):  # the fastest of five blocks: a neighbour's burst slows one block, not all
    start = time.process_time()
    for _ in range({n}):
        {op}
    best = min(best, (time.process_time() - start) / {n})
print(best)
"""


def export(ref: str, into: Path) -> Path:
    """The ``gimwatch`` package as committed at ``ref``, unpacked under ``into``."""
    archive = subprocess.run(
        ["git", "-C", str(ROOT), "archive", ref, "gimwatch"], check=True, capture_output=True
    ).stdout
    with tarfile.open(fileobj=BytesIO(archive)) as tar:
        tar.extractall(into, filter="data")
    return into


def time_case(tree: Path, name: str) -> float:
    """Seconds per operation of case ``name`` with ``tree`` first on the path."""
    setup, op, n = CASES[name]
    code = _TIMER.format(n=n, setup=setup, op=op)
    env = {
        **os.environ,
        "PYTHONPATH": str(tree),
        "OMP_NUM_THREADS": "1",
        "OPENBLAS_NUM_THREADS": "1",
        "PYTHONWARNINGS": "ignore",
    }
    out = subprocess.run(
        [sys.executable, "-c", code],
        check=True,
        capture_output=True,
        text=True,
        env=env,
        cwd=tree,
    )
    return float(out.stdout.split()[-1])


def main() -> None:
    """Time every case on both trees, interleaved, and write the ratios."""
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--old", required=True, help="the commit to compare against")
    parser.add_argument("--new", type=Path, default=ROOT, help="the tree to measure")
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--cases", nargs="*", default=list(CASES))
    parser.add_argument("--out", type=Path, default=ROOT / "benchmarks/hot_paths/before_after.csv")
    args = parser.parse_args()
    new_rev = subprocess.run(
        ["git", "-C", str(args.new), "rev-parse", "--short", "HEAD"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout.strip()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        old_tree = export(args.old, Path(tmp))
        for name in args.cases:
            old, new = [], []
            for round_ in range(args.rounds):  # old first, then new first: no order favoured
                pair = [(old_tree, old), (args.new, new)]
                for tree, times in pair if round_ % 2 == 0 else reversed(pair):
                    times.append(time_case(tree, name))
            row = {
                "case": name,
                "old_commit": args.old,
                "new_commit": new_rev,
                "old_median_us": round(statistics.median(old) * 1e6, 2),
                "new_median_us": round(statistics.median(new) * 1e6, 2),
                "ratio_new_over_old": round(statistics.median(new) / statistics.median(old), 3),
                "ratio_min": round(min(n / o for n, o in zip(new, old, strict=True)), 3),
                "ratio_max": round(max(n / o for n, o in zip(new, old, strict=True)), 3),
                "rounds": args.rounds,
            }
            rows.append(row)
            print(
                f"{name:22s} new/old {row['ratio_new_over_old']:.3f} "
                f"({row['ratio_min']:.3f}–{row['ratio_max']:.3f})",
                flush=True,
            )
    tmp_out = args.out.with_suffix(".tmp")
    with tmp_out.open("w", newline="") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    tmp_out.replace(args.out)


if __name__ == "__main__":
    main()
