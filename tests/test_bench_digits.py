"""Section ``digits``: its unit rewrite against the hand-written millimetre file, and what its
quick run measures against the invariants it claims (κ_S unit-free, Cholesky within κ_S·eps)."""

from __future__ import annotations

import csv
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest

from gimwatch.bench import BenchContext, digits

UNITS = Path(__file__).parent / "data" / "units"
EPS = np.finfo(float).eps


def _M(xml: str, q: np.ndarray) -> np.ndarray:
    model = pin.buildModelFromXML(xml)
    M = pin.crba(model, model.createData(), q)
    return np.triu(M) + np.triu(M, 1).T


def test_scaled_urdf_is_the_hand_written_millimetre_file():
    metres = (UNITS / "slider_arm_m.urdf").read_text()
    millimetres = (UNITS / "slider_arm_mm.urdf").read_text()
    q_m, q_mm = np.array([0.3, -0.8, 1.1, 0.025]), np.array([0.3, -0.8, 1.1, 25.0])
    np.testing.assert_allclose(
        _M(digits.scaled_urdf(metres, 1000.0), q_mm), _M(millimetres, q_mm), rtol=1e-12
    )
    # and M in millimetres is T M T, T = 1000 on the angles, 1 on the slide (kg·mm² units)
    T = np.diag([1000.0, 1000.0, 1000.0, 1.0])
    np.testing.assert_allclose(_M(millimetres, q_mm), T @ _M(metres, q_m) @ T, rtol=1e-12)


@pytest.fixture(scope="module")
def quick_rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("digits")
    result = digits.run(BenchContext(output=out, quick=True))
    assert result.figures[0].read_bytes()[:4] == b"\x89PNG"
    from gimwatch.bench.report import write_section

    write_section(out, result)
    with (out / "digits.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


def test_kappa_s_is_unit_free_and_kappa_is_not_in_the_study(quick_rows):
    rows = [r for r in quick_rows if r["solver"] == "crba_cho_solve"]
    key = lambda r: (r["case"], r["sample"])  # noqa: E731
    metres = {key(r): r for r in rows if r["unit"] == "m"}
    millimetres = {key(r): r for r in rows if r["unit"] == "mm"}
    assert metres.keys() == millimetres.keys()
    for k, a in metres.items():
        b = millimetres[k]
        assert float(b["kappa_equilibrated"]) == pytest.approx(
            float(a["kappa_equilibrated"]), rel=1e-9
        )
        if a["floating"] == "True":  # lengths and angles mix: κ follows the unit
            assert float(b["kappa"]) > 2 * float(a["kappa"])


def test_cholesky_stays_within_kappa_s_eps_in_the_energy_norm(quick_rows):
    for r in quick_rows:
        if r["solver"] in ("crba_cho_solve", "crba_pin_ldlt"):
            assert float(r["energy_error"]) <= float(r["kappa_equilibrated"]) * EPS, r
        assert float(r["kappa"]) <= float(r["diagonal_ratio"]) * float(r["kappa_equilibrated"]) * (
            1 + 1e-9
        )
