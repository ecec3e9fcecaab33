"""Registries: each kind of plug-in (metric, effect, integrator, ...) declared once, by name.

A `Registry` is a ``dict`` from name to class, filled by its `Registry.register` decorator,
so every reader (the scene schema, the command line's ``choices=``, the docs) sees the live
names in the order they were declared. An unknown name is refused with a suggestion from
`gimwatch.suggest`.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import ClassVar, Protocol, TypeVar

from gimwatch.errors import InputError
from gimwatch.suggest import did_you_mean

__all__ = ["Named", "Registry"]


class Named(Protocol):
    """What a registry holds: a class with its registered ``name``."""

    name: ClassVar[str]


T = TypeVar("T", bound=type[Named])


class Registry(dict[str, T]):
    """Name -> class, each name declared once (``kind`` says what, e.g. ``"metric"``)."""

    def __init__(self, kind: str, entries: Iterable[T] = ()) -> None:
        super().__init__()
        self.kind = kind
        for entry in entries:
            self.register(entry)

    def register(self, entry: T) -> T:
        """Class decorator: add ``entry`` under its ``name``.

        Raises:
            ValueError: The name is taken (a second declaration would hide the first).
        """
        if entry.name in self:
            raise ValueError(f"{self.kind} {entry.name!r} is already registered")
        self[entry.name] = entry
        return entry

    def names(self) -> tuple[str, ...]:
        """The registered names, in the order they were declared."""
        return tuple(self)

    def unknown(self, name: str) -> str:
        """``unknown KIND 'name'; did you mean 'x'?`` (the suggestion only when one is close)."""
        return f"unknown {self.kind} {name!r}{did_you_mean(name, self)}"

    def lookup(self, name: str) -> T:
        """The class registered as ``name``.

        Raises:
            InputError: No such name (the message lists the names, and suggests the closest).
        """
        if name not in self:
            hint = did_you_mean(name, self).removeprefix("; ")
            raise InputError(self.kind, f"one of {', '.join(self)}", name, hint=hint)
        return self[name]
