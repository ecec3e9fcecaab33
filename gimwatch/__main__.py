"""``python -m gimwatch`` and the ``gimwatch`` console script: `gimwatch.cli.startup`."""

from gimwatch.cli.startup import entry_point

__all__ = ["entry_point"]

if __name__ == "__main__":
    entry_point()
