"""The paper's claim in one table: δ, αδ and the κ tracker — cost and error side by side.

Shah & Saha (2013) offer δ (and αδ, Eq. 15) as a conditioning estimate "without incurring
expensive computation of the condition number". `claim_table` answers that from the
files ``gimwatch bench lean tracker -o benchmarks/cost`` writes (``lean.csv``,
``tracker_samples.csv``, ``tracker_claim.csv``): what one watch sample of each estimator
costs, against one ``pinocchio.aba`` call and against κ by CRBA + ``eigvalsh``, and how far it
is from κ along the paper's own trajectories. `update_cost_page` writes the table
between the ``<!-- cost:start -->`` and ``<!-- cost:end -->`` markers of a Markdown page
(``docs/findings/cost.md``); a test regenerates it from the committed files.
"""

from __future__ import annotations

import csv
import re
from pathlib import Path

from gimwatch.errors import InputError
from gimwatch.output.atomic import write_text_atomic

__all__ = ["COST_END", "COST_START", "claim_table", "tracker_targets", "update_cost_page"]

COST_START = "<!-- cost:start -->"
COST_END = "<!-- cost:end -->"
_ESTIMATORS = (
    ("delta", "δ = max M_ii / min M_ii (O(n) diagonal)"),
    ("alpha_delta", "αδ, α = κ(t0)/δ(t0) (Eq. 15)"),
    ("tracker", "κ tracker (warm-started Lanczos, shift-invert λmin, rtol 1e-10)"),
    ("kappa_eig", "κ by CRBA + `eigvalsh` (reference)"),
)


def _rows(folder: Path, name: str) -> list[dict]:
    path = folder / f"{name}.csv"
    if not path.is_file():
        raise InputError(str(path), "a CSV written by `gimwatch bench lean tracker`", "missing")
    with path.open(newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def _pct(x: float) -> str:
    return f"{100 * x:.2g} %" if x >= 1e-4 else f"{x:.1e}"


def claim_table(folder: str | Path) -> str:
    """The Markdown table (one row per estimator) from the bench files in ``folder``."""
    folder = Path(folder)
    lean = {int(r["n"]): r for r in _rows(folder, "lean")}
    claim = _rows(folder, "tracker_claim")
    samples = {(int(r["n"]), r["method"]): r for r in _rows(folder, "tracker_samples")}
    aba_20 = float(lean[20]["aba_call_us"])
    lines = [
        "| estimator | µs / sample, n = 20 | / one `aba` call | / κ-eig, n = 20 "
        "| / κ-eig, n = 200 | median error, n = 4 / 10 / 20 | max error, n = 4…20 |",
        "|---|---|---|---|---|---|---|",
    ]
    kappa_20 = next(
        float(r["sample_us"]) for r in claim if r["estimator"] == "kappa_eig" and r["n"] == "20"
    )
    for key, label in _ESTIMATORS:
        rows = {int(r["n"]): r for r in claim if r["estimator"] == key}
        cost = float(rows[20]["sample_us"])
        if key in ("delta", "alpha_delta"):
            at_200 = float(lean[200]["delta_watch_us"]) / float(lean[200]["kappa_eig_us"])
            at_200_text = f"{at_200:.2g}" + (" (as δ after t0)" if key == "alpha_delta" else "")
        elif key == "tracker":
            at_200_text = f"{float(samples[(200, 'tracker')]['vs_dense']):.2g}"
        else:
            at_200_text = "1"
        medians = " / ".join(_pct(float(rows[n]["median_rel_error"])) for n in (4, 10, 20))
        worst = max(float(rows[n]["max_rel_error"]) for n in (4, 10, 20))
        lines.append(
            f"| {label} | {cost:.3g} | {cost / aba_20:.2g} | {cost / kappa_20:.2g} "
            f"| {at_200_text} | {medians} | {_pct(worst)} |"
        )
    return "\n".join(lines)


def tracker_targets(folder: str | Path) -> str:
    """The tracker's targets, met or not, as the bench states them, from the files (a list)."""
    from gimwatch.bench.tracker_cost import verdicts

    folder = Path(folder)
    lines = verdicts(
        _rows(folder, "tracker_samples"),
        _rows(folder, "tracker_claim"),
        _rows(folder, "tracker_chain_1000"),
    )
    return "\n".join(f"- {line}" for line in lines)


def update_cost_page(page: str | Path, folder: str | Path) -> Path:
    """Replace the block between the cost markers of ``page`` with the table and the targets.

    The block is `claim_table`, a blank line, then `tracker_targets`.

    Raises:
        InputError: The page lacks the markers, or a bench file is missing.
    """
    page = Path(page)
    text = page.read_text(encoding="utf-8")
    pattern = re.compile(re.escape(COST_START) + r".*?" + re.escape(COST_END), re.DOTALL)
    if not pattern.search(text):
        raise InputError(str(page), f"a page with {COST_START} and {COST_END}", "no markers")
    block = "\n".join([COST_START, claim_table(folder), "", tracker_targets(folder), COST_END])
    return write_text_atomic(page, pattern.sub(lambda _: block, text))


def main(argv: list[str] | None = None) -> int:
    """``python -m gimwatch.bench.cost_page [PAGE [FOLDER]]``: regenerate the page's table."""
    import sys

    args = sys.argv[1:] if argv is None else argv
    page = args[0] if args else "docs/findings/cost.md"
    folder = args[1] if len(args) > 1 else "benchmarks/cost"
    update_cost_page(page, folder)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
