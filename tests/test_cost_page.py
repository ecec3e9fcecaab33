"""docs/findings/cost.md: its table is what the generator makes of the committed bench files."""

import csv
import shutil
from pathlib import Path

import pytest

from gimwatch.bench.cost_page import (
    COST_END,
    COST_START,
    claim_table,
    tracker_targets,
    update_cost_page,
)
from gimwatch.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "benchmarks" / "cost"
PAGE = ROOT / "docs" / "findings" / "cost.md"


def test_cost_table_is_generated_from_the_committed_files(tmp_path):
    copy = tmp_path / "cost.md"
    shutil.copy(PAGE, copy)
    update_cost_page(copy, FOLDER)
    assert copy.read_text(encoding="utf-8") == PAGE.read_text(encoding="utf-8"), (
        "run `python -m gimwatch.bench.cost_page docs/findings/cost.md benchmarks/cost`"
    )
    block = PAGE.read_text(encoding="utf-8").split(COST_START)[1].split(COST_END)[0]
    assert block.strip() == claim_table(FOLDER) + "\n\n" + tracker_targets(FOLDER)
    assert block.count("\n| ") == 5  # header separator + δ, αδ, tracker, κ-eig
    assert block.count("\n- ") == 5  # accuracy, n = 100, 200, 400, the 1,000-link scene


def test_the_table_quotes_the_files():
    """Spot-check the generator itself: the tracker's cost cell is the CSV's figure."""
    with (FOLDER / "tracker_claim.csv").open(newline="") as handle:
        rows = list(csv.DictReader(handle))
    tracker_20 = next(r for r in rows if r["estimator"] == "tracker" and r["n"] == "20")
    row = next(line for line in claim_table(FOLDER).splitlines() if "κ tracker" in line)
    assert row.split("|")[2].strip() == f"{float(tracker_20['sample_us']):.3g}"


def test_a_page_without_markers_is_refused(tmp_path):
    page = tmp_path / "page.md"
    page.write_text("no markers\n", encoding="utf-8")
    with pytest.raises(InputError, match="cost:start"):
        update_cost_page(page, FOLDER)
