"""Conditioning metrics of the GIM: κ, δ, pivots, matrix-free κ; one-shot analyses; the watch."""
