"""One runner for what a section times against what: per size, the calls compared, in one run.

A section that times calls at a series of sizes declares a `Comparison`, as SciPy's
``integrate._ivp`` declares its ``METHODS``: the table it fills, the sizes (full and quick),
how one size is set up (a `Case`: the named calls compared, each bound to one state, and
what the rows need besides) and how the size's timings become rows. `run_comparison` is the
loop every such section used to write by hand: each call timed by `time_call` (warm-up,
autorange, median of the rounds) with the rounds of the run's mode, a progress line per
call, the size's objects freed before the next size. Ratios are taken between medians of
the same run.

A case's calls may be a generator: a call built only when it is timed (a backend whose
Pinocchio Data takes gigabytes) is then freed before the next is built.
"""

from __future__ import annotations

import gc
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass, field
from typing import Any

from gimwatch.bench.records import BenchContext, Table
from gimwatch.bench.timing import Timing, time_call

__all__ = ["Case", "Comparison", "Rounds", "run_comparison"]

#: A call compared, or None when it cannot be timed at this size (the case says why).
Call = Callable[[], object] | None


@dataclass(frozen=True)
class Rounds:
    """How long each call is timed: rounds and the shortest round (s), full and quick."""

    repeats: int = 7
    min_round_s: float = 0.02
    quick_repeats: int = 3
    quick_min_round_s: float = 0.002

    def time(self, call: Callable[[], object], quick: bool) -> Timing:
        """`time_call` of ``call`` with this mode's rounds."""
        if quick:
            return time_call(call, repeats=self.quick_repeats, min_round_s=self.quick_min_round_s)
        return time_call(call, repeats=self.repeats, min_round_s=self.min_round_s)


@dataclass
class Case:
    """One size of a comparison: the calls compared and what its rows need besides.

    Attributes:
        label: Names the size in progress lines (``chain:20``).
        calls: ``{name: call}``, or ``(name, call)`` pairs from a generator (built when
            timed); a None call is not timed (its timing is None).
        facts: Whatever the rows need besides the timings (n, κ, notes, the objects timed).
        timings: Filled by the runner: each call's `Timing` (None: not timed), in call order.
    """

    label: str
    calls: Mapping[str, Call] | Iterable[tuple[str, Call]]
    facts: dict[str, Any] = field(default_factory=dict)
    timings: dict[str, Timing | None] = field(default_factory=dict)


@dataclass(frozen=True)
class Comparison:
    """What a section times against what, declared once.

    Attributes:
        table: The table's name (its CSV file is ``<table>.csv``).
        columns: The table's fixed columns.
        sizes: The sizes of a full run, each passed to ``case``.
        quick_sizes: The sizes of a quick (smoke) run.
        case: ``case(size, context)``: the size's `Case`, or None to skip the size (it
            reports why through ``context.progress``).
        rows: ``rows(case)``: the table rows of one size, its timings filled.
        rounds: How long each call is timed.
    """

    table: str
    columns: tuple[str, ...]
    sizes: tuple[Any, ...]
    quick_sizes: tuple[Any, ...]
    case: Callable[[Any, BenchContext], Case | None]
    rows: Callable[[Case], Iterable[dict[str, Any]]]
    rounds: Rounds = Rounds()


def run_comparison(comparison: Comparison, context: BenchContext) -> Table:
    """Time every call of every size of ``comparison``; the table of its rows."""
    table = Table(comparison.table, comparison.columns)
    for size in comparison.quick_sizes if context.quick else comparison.sizes:
        case = comparison.case(size, context)
        if case is None:
            continue
        calls = case.calls.items() if isinstance(case.calls, Mapping) else case.calls
        for name, call in calls:
            context.progress(f"  {case.label}: {name}")
            case.timings[name] = (
                None if call is None else comparison.rounds.time(call, context.quick)
            )
            del call  # a generator's next call may need the memory this one holds
        for row in comparison.rows(case):
            table.add(**row)
        del case, calls
        gc.collect()  # the size's Pinocchio Data (gigabytes past nv = 400) before the next
    return table
