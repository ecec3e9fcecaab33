"""Surveys across robots: random configurations and short trajectories, run in chunks, reported."""
