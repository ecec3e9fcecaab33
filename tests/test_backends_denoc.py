"""The DeNOC backend against Pinocchio's ABA (enabled when gimwatch.denoc lands)."""

import numpy as np

import gimwatch.denoc  # noqa: F401  (fails, not skips, when the DeNOC package is missing)
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.simulate import run_scene


def test_denoc_backend_gives_the_aba_trajectory():
    runs = {}
    for backend in ("aba", "denoc"):
        table = {
            "robot": "chain:4",
            "duration": 2.0,
            "sample": 0.1,
            "effects": {"gravity": {"vector": [0.0, -9.81, 0.0]}},
            "integrator": {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10},
            "dynamics": {"backend": backend},
        }
        runs[backend] = run_scene(parse_scene(table, source="t.toml"))
    assert np.abs(runs["aba"].q - runs["denoc"].q).max() < 1e-8
    assert np.abs(runs["aba"].v - runs["denoc"].v).max() < 1e-8 * max(
        1.0, np.abs(runs["aba"].v).max()
    )
