"""Why M(q) is ill-conditioned, where, and what would fix it.

* `gim_modes` — the eigenvectors of λmin and λmax in named joints and loaded bodies;
* `kappa_sensitivities` — exact ∂κ/∂p and elasticities for every inertial parameter,
  link offset and armature;
* `conditioning_map` / `trajectory_metrics` — κ, δ or any scalar registry metric
  over a grid of two joints or along a trajectory file;
* `minimal_armature` — the least armature that brings κ under a target, and its price.
"""

from __future__ import annotations

from gimwatch.explain.armature import ArmaturePlan, minimal_armature
from gimwatch.explain.maps import ConditioningMap, conditioning_map
from gimwatch.explain.modes import GimModes, Mode, gim_modes
from gimwatch.explain.sensitivity import KappaSensitivities, Sensitivity, kappa_sensitivities
from gimwatch.explain.trajectory import TrajectoryMetrics, trajectory_metrics

__all__ = [
    "ArmaturePlan",
    "ConditioningMap",
    "GimModes",
    "KappaSensitivities",
    "Mode",
    "Sensitivity",
    "TrajectoryMetrics",
    "conditioning_map",
    "gim_modes",
    "kappa_sensitivities",
    "minimal_armature",
    "trajectory_metrics",
]
