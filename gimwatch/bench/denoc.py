"""Time of DeNOC (numpy) against Pinocchio (C++) on spatial rod chains.

For each chain size n it times, at one seeded random state, the GIM (DeNOC Eqs. 11–13 vs
``pinocchio.crba``), its O(n) diagonal, inverse dynamics (vs ``rnea``) and forward dynamics
(Saha's UDUᵀ recursion vs ``aba``), and reports the median time per call and the ratio.
Pinocchio is not timed above nv = 400, where its Data would need several GB.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass

import numpy as np
import pinocchio as pin

from gimwatch.crosscheck import denoc_model
from gimwatch.errors import RobotError
from gimwatch.robots import DATA_NV_LIMIT, load_robot, random_configurations

__all__ = ["COLUMNS", "DenocTiming", "run"]

COLUMNS = ("n", "quantity", "denoc_s", "pinocchio_s", "ratio", "note")


@dataclass(frozen=True)
class DenocTiming:
    """Median seconds per call of one quantity at one chain size (nan when not measured)."""

    n: int
    quantity: str
    denoc_s: float
    pinocchio_s: float
    ratio: float
    note: str = ""

    def to_dict(self) -> dict:
        """The row as a dict with the :data:`COLUMNS` keys."""
        return asdict(self)


def _median_time(call: Callable[[], object], *, repeats: int, budget_s: float) -> float:
    """Median over ``repeats`` rounds of the mean time of a call (rounds sized to the budget)."""
    start = time.perf_counter()
    call()
    once = max(time.perf_counter() - start, 1e-7)
    number = max(1, int(budget_s / repeats / once))
    rounds = []
    for _ in range(repeats):
        start = time.perf_counter()
        for _ in range(number):
            call()
        rounds.append((time.perf_counter() - start) / number)
    return float(np.median(rounds))


def _cases(dm, model, data, q, v, a, tau) -> dict[str, tuple]:
    """(DeNOC call, Pinocchio call or None) per quantity, bound to one state."""
    return {
        "gim": (lambda: dm.gim(q), lambda: pin.crba(model, data, q)),
        "gim_diagonal": (lambda: dm.gim_diagonal(q), None),
        "inverse_dynamics": (
            lambda: dm.inverse_dynamics(q, v, a),
            lambda: pin.rnea(model, data, q, v, a),
        ),
        "forward_dynamics": (
            lambda: dm.forward_dynamics(q, v, tau),
            lambda: pin.aba(model, data, q, v, tau),
        ),
    }


def run(
    sizes: Sequence[int] = (10, 100, 500),
    *,
    repeats: int = 5,
    budget_s: float = 1.0,
    seed: int = 0,
    progress: Callable[[str], None] | None = None,
) -> list[DenocTiming]:
    """Time DeNOC and Pinocchio on ``chain:n`` (spatial axes) for each n in ``sizes``.

    Args:
        sizes: Chain lengths.
        repeats: Rounds per measurement (the median is kept).
        budget_s: Rough time budget of one measurement, s.
        seed: Seed of the random state.
        progress: Called with a short message before each chain (e.g. print to stderr).
    """
    rows: list[DenocTiming] = []
    for n in sizes:
        if progress is not None:
            progress(f"chain:{n}")
        robot = load_robot(f"chain:{n}")
        dm = denoc_model(robot)
        rng = np.random.default_rng(seed)
        q = random_configurations(robot, 1, seed=seed)[0]
        v, a, tau = (rng.standard_normal(robot.nv) for _ in range(3))
        try:
            data = robot.new_data()
            note = ""
        except RobotError:
            data, note = None, f"Pinocchio not timed: Data above nv = {DATA_NV_LIMIT} needs GB"
        cases = _cases(dm, robot.model, data, q, v, a, tau)
        for quantity, (denoc_call, pin_call) in cases.items():
            denoc_s = _median_time(denoc_call, repeats=repeats, budget_s=budget_s)
            pin_s = (
                _median_time(pin_call, repeats=repeats, budget_s=budget_s)
                if pin_call is not None and data is not None
                else float("nan")
            )
            why = note if data is None else ("no Pinocchio counterpart" if pin_call is None else "")
            rows.append(DenocTiming(n, quantity, denoc_s, pin_s, denoc_s / pin_s, why))
    return rows
