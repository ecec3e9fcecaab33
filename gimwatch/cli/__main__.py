"""``python -m gimwatch.cli``."""

from gimwatch.cli.startup import entry_point

entry_point()
