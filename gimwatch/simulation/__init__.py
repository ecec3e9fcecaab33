"""Scenes, effects, dynamics backends and integrators, and the results folder of a run."""
