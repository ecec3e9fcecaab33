import tomllib
from pathlib import Path

import numpy as np
import pytest
from closed_forms import rod_chain_gim

from gimwatch.demo import PAPER_CHAIN_LENGTHS, paper_chain_table, run_demo

SCENES = Path(__file__).resolve().parents[1] / "gimwatch" / "scenes"


@pytest.mark.parametrize("n", PAPER_CHAIN_LENGTHS)
def test_example_scene_files_are_the_demo_scenes(n):
    assert tomllib.loads((SCENES / f"chain_{n}.toml").read_text()) == paper_chain_table(n)


def test_short_demo_writes_figures_report_and_results(tmp_path):
    report = run_demo(tmp_path, lengths=(3, 5), duration_s=0.5, animate=5)
    text = report.read_text()
    for name in (
        "fig2_chain_3.png",
        "fig3_kappa_delta.png",
        "fig4_pivot_ratios.png",
        "fig5_kappa_scaled.png",
        "energy_drift.png",
        "chain_5/summary.json",
        "chain_5_swing.gif",
    ):
        assert (tmp_path / name).exists(), name
        assert name.split("/")[0] in text
    # at the straight start, kappa(chain_5) is numpy's on the closed-form M, delta = n^3
    values = np.linalg.eigvalsh(rod_chain_gim(np.zeros(5)))
    kappa = values[-1] / values[0]
    assert f"| 5 | {kappa:.6g} |" in text and "| 125 |" in text
