"""Typed access to a scene's TOML tables, each error a one-line ``source: key: problem``.

TOML integers have no size limit: ``duration = 999...9`` (400 digits) parses, and turning it
into a float raises `OverflowError`. Every number is converted here, so such a value
is a [`SceneError`][gimwatch.errors.SceneError] naming the key, like any other bad value.
"""

from __future__ import annotations

import math
from typing import Any

from gimwatch.errors import SceneError

__all__ = ["JointValues", "TableReader"]

JointValues = float | tuple[float, ...] | dict[str, float]


def _is_number(value: Any) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _describe(value: Any) -> str:
    """``repr`` of a value, shortened for integers too large to print on one line."""
    if isinstance(value, int) and not isinstance(value, bool) and abs(value) > 10**20:
        return f"an integer of {len(str(abs(value)))} digits"
    return repr(value)


class TableReader:
    """Typed access to a TOML table that reports errors as ``source: key: problem``."""

    def __init__(self, source: str, table: dict, prefix: str = "") -> None:
        self.source, self.table, self.prefix = source, table, prefix

    def key(self, name: str) -> str:
        """The full dotted key of ``name`` in this table."""
        return f"{self.prefix}{name}"

    def fail(self, name: str, problem: str) -> SceneError:
        """The [`SceneError`][gimwatch.errors.SceneError] about ``name`` in this table."""
        return SceneError(self.source, self.key(name), problem)

    def check_keys(self, allowed: set[str] | tuple[str, ...], required: tuple[str, ...] = ()):
        """Refuse keys not in ``allowed`` and missing ``required`` ones."""
        for name in self.table:
            if name not in allowed:
                raise self.fail(name, f"unknown key; expected one of {', '.join(sorted(allowed))}")
        for name in required:
            if name not in self.table:
                raise self.fail(name, "is required")

    def real(self, key: str, value: Any, rule: str = "finite") -> float:
        """``value`` (already known to be an int or float) as a finite float, else an error.

        ``key`` is the full key for the message (a list element or table entry included).
        """
        try:
            number = float(value)
        except OverflowError:
            number = math.inf
        if not math.isfinite(number):
            raise SceneError(self.source, key, f"must be {rule}, got {_describe(value)}")
        return number

    def number(
        self,
        name: str,
        default=None,
        *,
        positive=False,
        nonnegative=False,
        maximum: float = math.inf,
        minimum: float = -math.inf,
    ) -> float:
        """A finite number, optionally > 0, >= 0, and within [minimum, maximum]."""
        if name not in self.table:
            return default
        value = self.table[name]
        if not _is_number(value):
            raise self.fail(name, f"must be a number, got {value!r}")
        value = self.real(self.key(name), value)
        if positive and value <= 0:
            raise self.fail(name, f"must be > 0, got {value!r}")
        if nonnegative and value < 0:
            raise self.fail(name, f"must be >= 0, got {value!r}")
        if not minimum <= value <= maximum:
            rule = (
                f"<= {maximum:g}"
                if minimum == -math.inf
                else f">= {minimum:g}"
                if maximum == math.inf
                else f"within {minimum:g} .. {maximum:g}"
            )
            raise self.fail(name, f"must be {rule}, got {value!r}")
        return value

    def integer(self, name: str, default: int, *, minimum: int, maximum: int) -> int:
        """An integer within [minimum, maximum]."""
        if name not in self.table:
            return default
        value = self.table[name]
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(name, f"must be an integer, got {value!r}")
        if not minimum <= value <= maximum:
            raise self.fail(
                name, f"must be an integer from {minimum} to {maximum}, got {_describe(value)}"
            )
        return value

    def string(self, name: str, default=None, *, choices: tuple[str, ...] = ()) -> str:
        """A string, optionally one of ``choices``."""
        if name not in self.table:
            return default
        value = self.table[name]
        if not isinstance(value, str):
            raise self.fail(name, f"must be a string, got {value!r}")
        if choices and value not in choices:
            raise self.fail(name, f"must be one of {', '.join(choices)}, got {value!r}")
        return value

    def vector3(
        self, name: str, default: tuple[float, float, float] | None = None
    ) -> tuple[float, float, float] | None:
        """A list of 3 finite numbers (absent: ``default``)."""
        if name not in self.table:
            return default
        value = self.table[name]
        if not isinstance(value, list) or len(value) != 3 or not all(map(_is_number, value)):
            raise self.fail(name, f"must be a list of 3 numbers, got {value!r}")
        numbers = []
        for x in value:
            try:
                numbers.append(float(x))
            except OverflowError:
                numbers.append(math.inf)
        if not all(math.isfinite(x) for x in numbers):
            shown = ", ".join(_describe(x) for x in value)
            raise self.fail(name, f"must be finite, got [{shown}]")
        x, y, z = numbers
        return (x, y, z)

    def joint_values(
        self, name: str, default=None, *, nonnegative=False, bound=math.inf
    ) -> JointValues:
        """A number, a list (one per coordinate) or a ``{joint: number}`` table."""
        if name not in self.table:
            return default
        value = self.table[name]
        items: list[tuple[str, Any]]
        if isinstance(value, dict):
            items = [(f"{name}.{k}", v) for k, v in value.items()]
        elif isinstance(value, list):
            items = [(f"{name}[{i}]", v) for i, v in enumerate(value)]
            if not items:
                raise self.fail(name, "must not be an empty list")
        else:
            items = [(name, value)]
        numbers = []
        rule = "finite and >= 0" if nonnegative else "finite"
        for key, x in items:
            if not _is_number(x):
                raise self.fail(key, f"must be a number, got {x!r}")
            x = self.real(self.key(key), x, rule)
            if nonnegative and x < 0:
                raise self.fail(key, f"must be {rule}, got {x!r}")
            if abs(x) > bound:
                raise self.fail(key, f"must be within ±{bound:g}, got {x!r}")
            numbers.append(x)
        if isinstance(value, dict):
            return dict(zip(value, numbers, strict=True))
        if isinstance(value, list):
            return tuple(numbers)
        return numbers[0]

    def sub(self, name: str, default: dict | None = None) -> TableReader:
        """The reader of the sub-table ``name`` (absent: ``default`` or an empty table)."""
        value = self.table.get(name, default if default is not None else {})
        if not isinstance(value, dict):
            raise self.fail(name, f"must be a table, got {value!r}")
        return TableReader(self.source, value, f"{self.prefix}{name}.")
