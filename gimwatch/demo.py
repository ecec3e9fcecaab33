"""The main job: conditioning of the paper's straight 4-, 10- and 20-link chains."""

from __future__ import annotations

from pathlib import Path

from gimwatch.analysis import analyze_configuration
from gimwatch.results import write_json_atomic, write_text_atomic
from gimwatch.robots import load_robot, neutral_configuration

__all__ = ["PAPER_CHAIN_LENGTHS", "run_demo"]

PAPER_CHAIN_LENGTHS = (4, 10, 20)


def run_demo(output: Path) -> Path:
    """Analyse the paper's chains at the straight configuration; return the report path."""
    results = []
    for n in PAPER_CHAIN_LENGTHS:
        robot = load_robot(f"chain:{n}")
        results.append(analyze_configuration(robot, neutral_configuration(robot)))
    lines = [
        "# gimwatch demo: the paper's chains, straight",
        "",
        "| n | kappa | 4 n^4 | kappa / 4n^4 | delta | n^3 | pivot fwd | pivot bwd |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for n, r in zip(PAPER_CHAIN_LENGTHS, results, strict=True):
        lines.append(
            f"| {n} | {r.kappa:.6g} | {4 * n**4} | {r.kappa / (4 * n**4):.4f} | "
            f"{r.diagonal_ratio:.6g} | {n**3} | {r.pivot_ratio_forward:.4g} | "
            f"{r.pivot_ratio_backward:.4g} |"
        )
    write_json_atomic(output / "analysis.json", [r.to_dict() for r in results])
    return write_text_atomic(output / "report.md", "\n".join(lines) + "\n")
