"""Benchmarks: what accuracy and watching cost in time (measured here, never in tests)."""
