"""The package version, kept apart so that generated files can name it without cycles."""

__version__ = "0.1.0"
