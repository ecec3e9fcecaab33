"""``python -m gimwatch.cli``."""

from gimwatch.__main__ import entry_point

entry_point()
