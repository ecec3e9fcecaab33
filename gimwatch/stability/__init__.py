"""Will it explode? The largest stable timestep of a robot under its servos and integrator.

The robot is linearised where its servos hold it (`linear_system`), each integrator's one-step
map is built on that linear system (`step_maps`), and h* is where the map's spectral radius
reaches 1 (`timestep`); `analysis` puts it together, robot by robot.
"""

from __future__ import annotations

from gimwatch.stability.analysis import StabilityRecord, held_systems, stability
from gimwatch.stability.step_maps import INTEGRATORS
from gimwatch.stability.timestep import max_stable_timestep

__all__ = ["INTEGRATORS", "StabilityRecord", "held_systems", "max_stable_timestep", "stability"]
