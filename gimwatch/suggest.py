"""Suggestions for mistyped names (commands, metrics, robots): "did you mean ...?".

One helper so that every "unknown name" message reads the same way. Matching is
`difflib.get_close_matches` with a cutoff that catches transpositions and one or two
wrong letters (``kapa`` → ``kappa``, ``analyse`` → ``analyze``) but not unrelated words.
"""

from __future__ import annotations

import difflib
from collections.abc import Iterable

__all__ = ["CUTOFF", "did_you_mean"]

#: Similarity (0..1, difflib's ratio) a name needs to be suggested.
CUTOFF = 0.7


def did_you_mean(word: str, choices: Iterable[str]) -> str:
    """``"; did you mean 'x'?"`` (or ``'x' or 'y'``) for the closest choices, else ``""``."""
    close = difflib.get_close_matches(str(word), list(choices), n=3, cutoff=CUTOFF)
    return f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
