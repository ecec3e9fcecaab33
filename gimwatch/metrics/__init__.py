"""Conditioning metrics of the GIM: κ, δ, pivots, matrix-free κ, the κ tracker, one registry.

The watch that samples this registry along a trajectory lives in `gimwatch.watch`.
"""
