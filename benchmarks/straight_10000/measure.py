"""κ of the straight 10,000-link rod chain on the matrix-free route, and what ARPACK costs there.

The bench's ``longchain_kappa`` table stops at n = 4,000 (it also runs the dense eigensolver,
O(n³)); this records the n = 10,000 figures the docs quote: κ/4n⁴ from plain Lanczos on the
O(n) products M·x and M⁻¹·x (``gimwatch.bench.krylov_peers.plain_lanczos_kappa``, the O(n)
path's former engine, default seed and rtol), its
number of products, and the products restarted Lanczos (ARPACK through
``scipy.sparse.linalg.eigsh``, tol 1e-10, default basis) takes for the same two extreme
eigenvalues. One process, one core; about 3 minutes, most of it ARPACK.

Usage (from the repository root): python benchmarks/straight_10000/measure.py [--no-arpack]
Writes benchmarks/straight_10000/kappa.json.
"""

from __future__ import annotations

import datetime
import json
import sys
import time
from pathlib import Path

import numpy as np
import scipy
from scipy.sparse.linalg import LinearOperator, eigsh

import gimwatch
from gimwatch.bench.krylov_peers import plain_lanczos_kappa
from gimwatch.denoc import DenocModel
from gimwatch.model.chains import chain_spec

N = 10_000
OUT = Path(__file__).with_name("kappa.json")


def _arpack_products(apply, n: int) -> tuple[float, int]:
    count = 0

    def counted(x):
        nonlocal count
        count += 1
        return apply(np.ravel(x))

    operator = LinearOperator((n, n), matvec=counted, dtype=float)
    start = np.random.default_rng(0).standard_normal(n)
    value = eigsh(operator, k=1, which="LA", tol=1e-10, v0=start, return_eigenvectors=False)
    return float(value[0]), count


def main() -> int:
    state = DenocModel.from_chain(chain_spec(N)).state(np.zeros(N))
    began = time.perf_counter()
    found = plain_lanczos_kappa(state)
    record = {
        "n": N,
        "made_by": "python benchmarks/straight_10000/measure.py (one process, one core)",
        "date": datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%d %H:%M UTC"),
        "versions": {
            "gimwatch": gimwatch.__version__,
            "numpy": np.__version__,
            "scipy": scipy.__version__,
        },
        "lanczos": {
            "kappa": found.kappa,
            "kappa_over_4n4": found.kappa / (4 * N**4),
            "lambda_min": found.lambda_min,
            "lambda_max": found.lambda_max,
            "products": found.products,
            "last_relative_change": found.last_relative_change,
            "seconds": time.perf_counter() - began,
        },
    }
    if "--no-arpack" not in sys.argv:
        began = time.perf_counter()
        lambda_max, products_max = _arpack_products(state.matvec, N)
        inverse_max, products_min = _arpack_products(state.solve, N)
        record["arpack"] = {
            "kappa": lambda_max * inverse_max,
            "products": products_max + products_min,
            "seconds": time.perf_counter() - began,
        }
    OUT.write_text(json.dumps(record, indent=2) + "\n", encoding="utf-8")
    print(json.dumps(record, indent=2))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
