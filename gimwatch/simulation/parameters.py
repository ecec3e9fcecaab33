"""Declared parameters: what an effect or a torque law reads from its scene table.

Each effect ([`gimwatch.simulation.effects`][gimwatch.simulation.effects]) and torque law
([`gimwatch.simulation.torque_laws`][gimwatch.simulation.torque_laws]) lists its parameters as
`Parameter` records; the scene reader ([`gimwatch.simulation.scene`][gimwatch.simulation.scene])
validates a table against them and the scene reference (``docs/scenes.md``) is generated from them,
so a new effect or law declares its keys in one place.
"""

from __future__ import annotations

from collections.abc import Collection
from dataclasses import dataclass
from typing import Any

__all__ = ["KINDS", "Parameter"]

#: The value kinds a parameter may have.
KINDS = ("number", "joint", "configuration", "vector3", "string")


@dataclass(frozen=True, eq=False)
class Parameter:
    """One key of an effect's or torque law's table.

    Attributes:
        name: The TOML key.
        kind: ``"number"`` (a float), ``"joint"`` (joint-indexed: number, list or
            ``{joint = value}`` table, in velocity coordinates), ``"configuration"`` (like
            ``joint`` but a configuration: continuous joints by angle), ``"vector3"``
            (3 numbers) or ``"string"``.
        required: Whether the key must be given.
        default: Value when the key is absent (None: absent stays absent).
        positive: A number must be > 0.
        nonnegative: Every number must be >= 0.
        choices: Allowed strings (a registry dict stays live: its keys at read time).
        doc: One line for the scene reference (units included).
    """

    name: str
    kind: str
    required: bool = False
    default: Any = None
    positive: bool = False
    nonnegative: bool = False
    choices: Collection[str] = ()
    doc: str = ""

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"Parameter kind must be one of {KINDS}, got {self.kind!r}")
