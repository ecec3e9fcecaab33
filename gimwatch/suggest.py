"""Suggestions for mistyped names (commands, metrics, robots): "did you mean ...?".

One helper so that every "unknown name" message reads the same way. Matching is
`difflib.get_close_matches` with a cutoff that catches transpositions and one or two
wrong letters (``kapa`` → ``kappa``, ``analyse`` → ``analyze``) but not unrelated words.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = ["CUTOFF", "close_matches", "did_you_mean"]

#: Similarity (0..1, difflib's ratio) a name needs to be suggested.
CUTOFF = 0.7


def close_matches(word: str, choices: Iterable[str], *, cutoff: float = CUTOFF) -> list[str]:
    """Up to three choices closest to ``word``, best first, ignoring case (``UR5`` → ``ur5``)."""
    by_folded: dict[str, str] = {}
    for choice in choices:
        by_folded.setdefault(str(choice).casefold(), str(choice))
    close = difflib.get_close_matches(str(word).casefold(), list(by_folded), n=3, cutoff=cutoff)
    return [by_folded[c] for c in close]


def did_you_mean(word: str, choices: Iterable[str], *, cutoff: float = CUTOFF) -> str:
    """``"; did you mean 'x'?"`` (or ``'x' or 'y'``) for the closest choices, else ``""``."""
    close = close_matches(word, choices, cutoff=cutoff)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
