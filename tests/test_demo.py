import tomllib
from pathlib import Path

import numpy as np
import pytest
from closed_forms import rod_chain_gim

from gimwatch.demo import PAPER_CHAIN_LENGTHS, paper_chain_table, run_demo

SCENES = Path(__file__).resolve().parents[1] / "gimwatch" / "scenes"


def test_the_demo_chain_is_the_papers_setting():
    """The one source of the demo's settings (the bundled scene) says what the paper says."""
    table = paper_chain_table(7)  # no chain_7.toml: chain_4's settings, 7 links
    assert table["robot"] == "chain:7"
    assert (table["q"], table["v"]) == (0.0, 0.0)  # straight and horizontal, at rest
    assert table["effects"] == {"gravity": {"vector": [0.0, -9.81, 0.0]}}  # in the plane
    assert table["integrator"] == {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10}
    assert (table["duration"], table["sample"]) == (5.0, 0.01)
    short = paper_chain_table(7, duration_s=0.5, sample_s=0.02)
    assert (short["duration"], short["sample"]) == (0.5, 0.02)
    assert {**short, "duration": 5.0, "sample": 0.01} == table


@pytest.mark.parametrize("n", PAPER_CHAIN_LENGTHS)
def test_the_demo_reads_the_bundled_scene_of_each_paper_chain(n, tmp_path, monkeypatch):
    path = SCENES / f"chain_{n}.toml"
    assert paper_chain_table(n) == tomllib.loads(path.read_text())
    # read, not restated: a change to the file is a change to the demo
    edited = tmp_path / "scenes"
    edited.mkdir()
    for scene in SCENES.glob("*.toml"):
        text = scene.read_text().replace("rtol = 1e-10", "rtol = 1e-9")
        (edited / scene.name).write_text(text)
    monkeypatch.setattr("gimwatch.simulation.bundled_scenes.SCENES_DIR", edited)
    assert paper_chain_table(n)["integrator"]["rtol"] == 1e-9


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
