"""Memory of a Pinocchio Data for the paper's n-link chain: after it is built, and at its peak.

Each size runs in a fresh process: load ``chain:n`` (built from its ChainSpec, no Data), read
VmRSS, build ``model.createData()``, then read VmRSS again and the peak VmHWM (construction
holds a temporary copy, so the peak is about twice the final size). Sizes stop at n = 250
(peak ≈ 1 GB) to stay small on a shared machine; the docs extrapolate as n³ from the largest.

Usage (from the repository root): python benchmarks/pinocchio_data/measure.py
Writes benchmarks/pinocchio_data/memory.csv.
"""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

SIZES = (50, 100, 150, 200, 250)
OUT = Path(__file__).with_name("memory.csv")
_PROBE = """
import sys
import gimwatch as gw

def status(key):
    with open("/proc/self/status") as handle:
        for line in handle:
            if line.startswith(key):
                return int(line.split()[1]) * 1024

robot = gw.load_robot(f"chain:{sys.argv[1]}")
before = status("VmRSS:")
data = robot.model.createData()
print(status("VmRSS:") - before, status("VmHWM:") - before)
"""


def main() -> int:
    rows = []
    for n in SIZES:
        done = subprocess.run(
            [sys.executable, "-c", _PROBE, str(n)], capture_output=True, text=True, check=True
        )
        final, peak = (int(x) for x in done.stdout.split())
        rows.append({"n": n, "data_bytes": final, "peak_bytes": peak})
        print(rows[-1], flush=True)
    with OUT.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=["n", "data_bytes", "peak_bytes"])
        writer.writeheader()
        writer.writerows(rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
