"""Splice benchmarks/survey/table.md into README.md between the survey-table markers.

Run by `make survey` after `gimwatch survey all --samples 200 -o benchmarks/survey`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from gimwatch.results import write_text_atomic

BEGIN, END = "<!-- survey-table:begin -->", "<!-- survey-table:end -->"


def main(root: Path) -> int:
    folder = root / "benchmarks" / "survey"
    record = json.loads((folder / "survey.json").read_text())
    failed = ", ".join(f"`{f['spec']}` ({f['stage']})" for f in record["failures"]) or "none"
    body = (
        f"{len(record['robots'])} robots, {record['samples_per_robot']} random configurations "
        f"each + the neutral one, seed {record['seed']} (`make survey`; full report: "
        f"[benchmarks/survey/report.md](benchmarks/survey/report.md)). Not surveyed: {failed}.\n\n"
        + (folder / "table.md").read_text()
        + "\n`*`: no joint with a fixed base, surveyed with a free-flyer base. "
        "`—`: undefined (κ or δ is the same at every sample).\n"
    )
    readme = root / "README.md"
    text = readme.read_text()
    if BEGIN not in text or END not in text:
        print(f"{readme}: no {BEGIN} ... {END} markers", file=sys.stderr)
        return 1
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    write_text_atomic(readme, f"{head}{BEGIN}\n{body}{END}{tail}")
    return 0


if __name__ == "__main__":
    sys.exit(main(Path(__file__).resolve().parents[2]))
