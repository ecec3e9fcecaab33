"""Benchmarks: what accuracy and independence cost in time (never run by the tests' timers)."""
