"""The bench's one runner: every declared call timed per size, rows from its timings."""

import gc
import weakref

import pytest

from gimwatch.bench.compare import Case, Comparison, Rounds, run_comparison
from gimwatch.bench.records import BenchContext

FAST = Rounds(repeats=2, min_round_s=1e-4, quick_repeats=2, quick_min_round_s=1e-4)


def _context(tmp_path, quick=False):
    lines = []
    return BenchContext(output=tmp_path, quick=quick, progress=lines.append), lines


def test_every_call_is_timed_per_size_and_rows_read_the_timings(tmp_path):
    counts = {}

    def case(n, context):
        def call(name):
            def run():
                counts[(n, name)] = counts.get((n, name), 0) + 1

            return run

        return Case(f"n = {n}", {"a": call("a"), "b": call("b"), "skipped": None}, {"n": n})

    def rows(case):
        a, b = case.timings["a"], case.timings["b"]
        assert case.timings["skipped"] is None
        yield {"n": case.facts["n"], "calls_a": a.number, "ratio": b.median_s / a.median_s}

    comparison = Comparison("t", ("n", "calls_a", "ratio"), (2, 3), (1,), case, rows, FAST)
    context, lines = _context(tmp_path)
    table = run_comparison(comparison, context)
    assert [r["n"] for r in table.rows] == [2, 3]
    for row in table.rows:
        # warm-up (2), the autorange rounds, then 2 timed rounds of `number` calls each
        assert counts[(row["n"], "a")] >= 2 + 2 * row["calls_a"]
        assert row["ratio"] > 0
    assert lines == [f"  n = {n}: {name}" for n in (2, 3) for name in ("a", "b", "skipped")]
    quick = run_comparison(comparison, _context(tmp_path, quick=True)[0])
    assert [r["n"] for r in quick.rows] == [1]


def test_a_case_of_none_skips_its_size(tmp_path):
    def case(n, context):
        return None if n == 2 else Case(f"n = {n}", {"a": lambda: None}, {"n": n})

    comparison = Comparison(
        "t", ("n",), (1, 2, 3), (1,), case, lambda c: [{"n": c.facts["n"]}], FAST
    )
    assert [r["n"] for r in run_comparison(comparison, _context(tmp_path)[0]).rows] == [1, 3]


class _Big:
    """Stands for a backend holding a large Pinocchio Data."""

    def __call__(self):
        return None


def test_a_generated_call_is_freed_before_the_next_is_built(tmp_path):
    alive = []

    def calls():
        for name in ("first", "second", "third"):
            gc.collect()
            assert all(ref() is None for ref in alive), f"a previous call outlived it: {name}"
            big = _Big()
            alive.append(weakref.ref(big))
            yield name, big
            del big

    comparison = Comparison(
        "t",
        ("names",),
        (1,),
        (1,),
        lambda n, context: Case("one", calls()),
        lambda c: [{"names": ",".join(c.timings)}],
        FAST,
    )
    table = run_comparison(comparison, _context(tmp_path)[0])
    assert table.rows == [{"names": "first,second,third"}]
    assert len(alive) == 3


def test_a_row_without_the_table_columns_is_refused(tmp_path):
    comparison = Comparison(
        "t", ("n",), (1,), (1,), lambda n, c: Case("one", {}), lambda c: [{"m": 1}], FAST
    )
    with pytest.raises(KeyError, match="missing"):
        run_comparison(comparison, _context(tmp_path)[0])
