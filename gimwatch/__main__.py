"""``python -m gimwatch``."""

from gimwatch.cli import _entry_point

_entry_point()
