"""Splice benchmarks/survey/table.md into docs/findings/survey.md between the survey-table markers.

Run by `make survey` after `gimwatch survey all --fixed --samples 200 --trajectory -o benchmarks/survey`.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from gimwatch.output.atomic import write_text_atomic

BEGIN, END = "<!-- survey-table:begin -->", "<!-- survey-table:end -->"


def main(root: Path) -> int:
    folder = root / "benchmarks" / "survey"
    record = json.loads((folder / "survey.json").read_text())
    failed = ", ".join(f"`{f['spec']}` ({f['stage']})" for f in record["failures"]) or "none"
    runs = record.get("trajectory_settings")
    along = (
        ""
        if runs is None
        else f" Along runs: {runs['runs_per_robot']} simulated runs of {runs['duration_s']:g} s "
        "per robot, falling from random samples under gravity with light damping, α at t0 of "
        "each run (details in the report)."
    )
    body = (
        f"{len(record['robots'])} robots, {record['samples_per_robot']} random configurations "
        f"each + the neutral one, seed {record['seed']} (`make survey`; full report: "
        f"`benchmarks/survey/report.md`). Not surveyed: {failed}."
        f"{along}\n\n"
        + (folder / "table.md").read_text()
        + "\n`*`: no joint with a fixed base, surveyed with a free-flyer base. "
        "`—`: undefined (κ or δ is the same at every sample)."
        + ("" if runs is None else " `†`: floating base, not simulated (free fall).")
        + "\n"
    )
    readme = root / "docs" / "findings" / "survey.md"
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
