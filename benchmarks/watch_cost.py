"""Watch overhead per integration step: write CSV + Markdown, print the table.

Usage: python benchmarks/watch_cost.py [-o DIR]
"""

import argparse
import datetime
import os
import platform
from pathlib import Path

from threadpoolctl import threadpool_limits

from gimwatch.bench.watch import COLUMNS, run
from gimwatch.results import write_text_atomic
from gimwatch.simresults import versions


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("-o", "--output", default="bench-output")
    args = parser.parse_args()
    with threadpool_limits(limits=1, user_api="blas"):
        rows = run()
    out = Path(args.output)
    csv = [",".join(COLUMNS)] + [",".join(str(row[c]) for c in COLUMNS) for row in rows]
    write_text_atomic(out / "watch_cost.csv", "\n".join(csv) + "\n")
    info = versions()
    lines = [
        "# Watch cost per RK4 step (watch every 10 steps)",
        "",
        f"{datetime.datetime.now().isoformat(timespec='seconds')}, "
        f"{platform.processor() or platform.machine()}, {os.cpu_count()} CPUs, "
        + ", ".join(f"{k} {v}" for k, v in info.items()),
        "",
        "| n | watch | step (µs) | run overhead vs bare | one sample (µs) "
        "| sample cost / bare step, amortized | one ABA call (µs) |",
        "|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['n']} | {r['watch']} | {r['step_us']:.1f} | {r['overhead_vs_bare']:+.1%} | "
            f"{r['per_sample_us']:.1f} | {r['amortized_overhead']:.1%} | {r['aba_call_us']:.2f} |"
        )
    text = "\n".join(lines) + "\n"
    write_text_atomic(out / "watch_cost.md", text)
    print(text)


if __name__ == "__main__":
    main()
