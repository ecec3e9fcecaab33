"""The house rule ruff does not hold: every function body in gimwatch/ is at most 60 lines.

A body is counted from its first statement after the docstring to its last line (comments
and blank lines inside count: they are what a reader scrolls through). ruff holds the rest
of the house rules (complexity, branches, statements, arguments: ``[tool.ruff.lint]`` in
pyproject.toml). The exceptions are numba kernels and data tables, each listed with its
reason; the list is checked not to go stale.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "gimwatch"
MAX_BODY_LINES = 60

#: (module, function) -> why its body may be longer than MAX_BODY_LINES.
EXCEPTIONS = {
    ("gimwatch/denoc/fused.py", "_poses"): (
        "numba kernel: one compiled loop over the bodies, a branch per joint kind"
    ),
    ("gimwatch/denoc/fused.py", "_velocity_terms"): (
        "numba kernel: the velocity recursion per joint kind, one compiled loop"
    ),
    ("gimwatch/denoc/fused.py", "_articulated_pass"): (
        "numba kernel: the articulated-body pass per joint kind, one compiled loop"
    ),
    ("gimwatch/denoc/fused.py", "gim_diagonal"): (
        "numba kernel: the O(n) diagonal per joint kind, one compiled loop"
    ),
    ("gimwatch/stress/cases.py", "_cases"): (
        "data table: the stress suite's cases, one literal entry each"
    ),
}


def _body_lines(function: ast.FunctionDef | ast.AsyncFunctionDef) -> int:
    """Lines from the first statement after the docstring to the function's last line."""
    body = function.body
    if ast.get_docstring(function, clean=False) is not None:
        body = body[1:]
    if not body:
        return 0
    return (function.end_lineno or body[-1].lineno) - body[0].lineno + 1


def _function_lengths() -> dict[tuple[str, str], int]:
    """(module, qualified-ish name) -> body lines, for every function and method."""
    lengths: dict[tuple[str, str], int] = {}
    for path in sorted(PACKAGE.rglob("*.py")):
        module = path.relative_to(ROOT).as_posix()
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, (ast.FunctionDef, ast.AsyncFunctionDef)):
                key = (module, node.name)
                lengths[key] = max(lengths.get(key, 0), _body_lines(node))
    return lengths


def test_function_bodies_are_at_most_60_lines():
    long = {
        key: n
        for key, n in _function_lengths().items()
        if n > MAX_BODY_LINES and key not in EXCEPTIONS
    }
    assert not long, (
        f"{len(long)} function(s) in gimwatch/ have bodies over {MAX_BODY_LINES} lines "
        "(docstring excluded); split them, or list a numba kernel or data table in "
        "EXCEPTIONS with its reason:\n"
        + "\n".join(f"  {module}: {name} ({n} lines)" for (module, name), n in sorted(long.items()))
    )


def test_every_exception_exists_and_is_still_long():
    lengths = _function_lengths()
    stale = [
        f"  {module}: {name} "
        + ("does not exist" if (module, name) not in lengths else f"is {lengths[module, name]}")
        for module, name in EXCEPTIONS
        if lengths.get((module, name), 0) <= MAX_BODY_LINES
    ]
    assert not stale, "EXCEPTIONS lists functions that need no exception; delete:\n" + "\n".join(
        stale
    )


def test_every_exception_has_a_reason():
    assert all(reason.strip() for reason in EXCEPTIONS.values())


def test_the_counter_excludes_the_docstring_and_counts_the_rest():
    source = 'def f():\n    """Doc.\n\n    More.\n    """\n    x = 1\n\n    # why\n    return x\n'
    (function,) = ast.parse(source).body
    assert isinstance(function, ast.FunctionDef)
    assert _body_lines(function) == 4
