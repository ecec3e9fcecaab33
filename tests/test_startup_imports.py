"""First contact imports only what its path needs (the time is measured by `bench startup`).

``gimwatch analyze`` of a small robot (dense CRBA) and the first names of a script never
import numba (its import and the compiled DeNOC kernels: ~0.2 s) nor SciPy's sparse solvers
(ARPACK, ~0.3 s); those load when a path that uses them runs (DeNOC, the matrix-free κ).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HEAVY = ("numba", "scipy.sparse.linalg", "gimwatch.denoc")


def _modules_after(code: str, cwd: Path) -> set[str]:
    probe = f"{code}\nimport json, sys\nprint(json.dumps(sorted(sys.modules)))"
    done = subprocess.run(
        [sys.executable, "-c", probe],
        cwd=cwd,
        env={**os.environ, "PYTHONPATH": str(ROOT)},
        capture_output=True,
        text=True,
        check=True,
    )
    return set(json.loads(done.stdout.strip().splitlines()[-1]))


@pytest.mark.parametrize(
    "code",
    [
        "from gimwatch.cli import main; main(['analyze', 'ur5'])",
        "from gimwatch.cli import main; main(['analyze', 'chain:6', '--random', '3', '--json'])",
        "import gimwatch as gw; r = gw.load_robot('ur5'); "
        "gw.condition_number(gw.gim(r, gw.neutral_configuration(r)))",
    ],
)
def test_the_dense_path_imports_neither_numba_nor_arpack(code, tmp_path):
    loaded = _modules_after(code, tmp_path)
    assert not [name for name in HEAVY if name in loaded]


def test_a_kappa_watch_loads_its_compiled_kernels_but_not_arpack(tmp_path):
    """A watch samples in a loop: its κ is one compiled call (numba, cached kernels), worth
    the import for every sample after the first; ARPACK and DeNOC stay out of a κ watch."""
    loaded = _modules_after(
        "import gimwatch as gw; r = gw.load_robot('ur5'); w = gw.Watch(r, ('kappa',)); "
        "w.sample(0.0, gw.neutral_configuration(r))",
        tmp_path,
    )
    assert "numba" in loaded
    assert not [name for name in ("scipy.sparse.linalg", "gimwatch.denoc") if name in loaded]


def test_a_path_that_needs_them_still_gets_them(tmp_path):
    loaded = _modules_after(
        "import gimwatch as gw; r = gw.load_robot('ur5'); "
        "w = gw.Watch(r, ('kappa_lanczos',)); w.sample(0.0, gw.neutral_configuration(r))",
        tmp_path,
    )
    # the matrix-free κ runs on the tracker's Krylov engine (compiled), not on ARPACK
    assert "gimwatch.metrics.tracker.krylov" in loaded
    assert "gimwatch.bench.krylov_peers" not in loaded
