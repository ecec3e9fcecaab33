"""Reading time against file size for hostile prologs (issue: a nested regex hung on xacro
headers). Run: ``python benchmarks/linear_reading.py`` -> benchmarks/linear_reading.csv.

Each row: a shape, its size in bytes, and the median of 3 ``load_robot`` calls (s); time per
byte stays flat (linear reading) across two decades of size.
"""

from __future__ import annotations

import csv
import statistics
import sys
import tempfile
import time
import warnings
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))

from real_shapes import arm

from gimwatch.errors import GimwatchError
from gimwatch.model.robots import load_robot

SHAPES = {
    "leading_comments": lambda n: "<!-- c -->\n" * n + arm(),
    "one_long_comment": lambda n: "<!--" + "x" * (100 * n) + "-->\n" + arm().split("?>", 1)[1],
    "unclosed_comments": lambda n: arm().replace("</robot>", "<!-- " * n + "</robot>"),
}


def main() -> None:
    """Time each shape at three sizes and write the CSV."""
    warnings.simplefilter("ignore")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        for shape, make in SHAPES.items():
            for n in (1_000, 10_000, 100_000):
                path = Path(folder) / f"{shape}_{n}.urdf"
                path.write_text(make(n), encoding="utf-8")
                times = []
                for _ in range(3):
                    start = time.perf_counter()
                    try:
                        load_robot(path)
                    except GimwatchError:
                        pass
                    times.append(time.perf_counter() - start)
                size = path.stat().st_size
                median = statistics.median(times)
                rows.append(
                    {
                        "shape": shape,
                        "bytes": size,
                        "median_s": f"{median:.4g}",
                        "ns_per_byte": f"{1e9 * median / size:.3g}",
                    }
                )
    out = Path(__file__).with_suffix(".csv")
    with out.open("w", newline="", encoding="utf-8") as handle:
        writer = csv.DictWriter(handle, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(out.read_text(encoding="utf-8"))


if __name__ == "__main__":
    main()
