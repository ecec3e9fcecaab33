"""DeNOC (numpy) vs Pinocchio (C++): GIM, inverse and forward dynamics on n-link chains.

Usage: python benchmarks/denoc_vs_pinocchio.py [-o DIR] [--sizes 10 100 500]
Writes DIR/denoc_vs_pinocchio.csv and DIR/denoc_vs_pinocchio.md (default DIR: benchmarks/results).
"""

from __future__ import annotations

import argparse
import csv
import datetime
import io
import platform
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits

# run from a checkout: import this checkout's gimwatch, not an installed one
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from gimwatch import __version__
from gimwatch.bench.denoc import COLUMNS, run
from gimwatch.environment import cpu_model
from gimwatch.results import write_text_atomic


def _fmt(x: float) -> str:
    return "n/a" if not np.isfinite(x) else f"{x * 1e6:.1f}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-o", "--output", type=Path, default=Path(__file__).parent / "results")
    parser.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 500])
    args = parser.parse_args(argv)
    with threadpool_limits(limits=1, user_api="blas"):
        rows = run(args.sizes, progress=lambda m: print(f"timing {m}", file=sys.stderr))
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=COLUMNS, lineterminator="\n")
    writer.writeheader()
    writer.writerows(r.to_dict() for r in rows)
    write_text_atomic(args.output / "denoc_vs_pinocchio.csv", buffer.getvalue())
    lines = [
        "# DeNOC (numpy) vs Pinocchio (C++)",
        "",
        f"gimwatch {__version__}, Pinocchio {pin.__version__}, numpy {np.__version__}, "
        f"Python {platform.python_version()}; {datetime.date.today()}; {cpu_model()}; "
        "BLAS 1 thread.",
        "Median time per call (µs) on chain:n (paper rods), one random state; "
        "ratio = DeNOC / Pinocchio.",
        "",
        "| n | quantity | DeNOC µs | Pinocchio µs | ratio | note |",
        "|---:|---|---:|---:|---:|---|",
    ]
    for r in rows:
        ratio = "n/a" if not np.isfinite(r.ratio) else f"{r.ratio:.0f}×"
        cells = [str(r.n), r.quantity, _fmt(r.denoc_s), _fmt(r.pinocchio_s), ratio, r.note]
        lines.append("| " + " | ".join(cells) + " |")
    text = "\n".join(lines) + "\n"
    write_text_atomic(args.output / "denoc_vs_pinocchio.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
