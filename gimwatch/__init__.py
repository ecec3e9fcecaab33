"""gimwatch: watch the conditioning of a robot's generalized inertia matrix (GIM).

Importing gimwatch does no work: no robot is loaded, nothing is written, and no submodule is
imported until one of its names is first used (PEP 562). ``gimwatch.load_robot`` imports
``gimwatch.model.robots`` on first access; every name of `__all__` is reachable this
way, and ``from gimwatch import X`` works as usual.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

from gimwatch._version import __version__

if TYPE_CHECKING:  # what type checkers and IDEs see; at run time __getattr__ imports
    from gimwatch.crosscheck import CrossCheckResult, crosscheck_robot
    from gimwatch.denoc import DenocModel
    from gimwatch.errors import (
        BackendWarning,
        ConditioningError,
        ExampleRobotWarning,
        GimwatchError,
        GimwatchWarning,
        IllConditionedWarning,
        InputError,
        OutputError,
        RobotError,
        SceneError,
        SimulationError,
        URDFError,
        URDFWarning,
    )
    from gimwatch.explain.armature import ArmaturePlan, minimal_armature
    from gimwatch.explain.maps import ConditioningMap, conditioning_map
    from gimwatch.explain.modes import GimModes, gim_modes
    from gimwatch.explain.sensitivity import KappaSensitivities, Sensitivity, kappa_sensitivities
    from gimwatch.explain.trajectory import TrajectoryMetrics, trajectory_metrics
    from gimwatch.metrics.analyze import analyze
    from gimwatch.metrics.conditioning import (
        ScaledDiagonalRatio,
        check_gim,
        condition_estimate_1norm,
        condition_number,
        diagonal_ratio,
        eigenvalues,
        ldlt_pivots,
        pivot_ratio_backward,
        pivot_ratio_forward,
        udut_pivots,
    )
    from gimwatch.metrics.dense_analysis import GimAnalysis, analyze_configuration
    from gimwatch.metrics.estimator_quality import estimator_quality
    from gimwatch.metrics.tracker import KappaTracker, TrackedKappa, TrackerSettings, track_kappa
    from gimwatch.model.chains import ChainSpec, chain_spec, generate_chain_urdf, write_chain_urdf
    from gimwatch.model.example_robots import example_robot_names
    from gimwatch.model.inertia import gim, gim_diagonal
    from gimwatch.model.robot_spec import RobotSpec, default_floating
    from gimwatch.model.robots import Robot, load_robot, neutral_configuration
    from gimwatch.model.sampling import random_configurations
    from gimwatch.simulation.bundled_scenes import bundled_scenes
    from gimwatch.simulation.results_folder import summarize, write_simulation
    from gimwatch.simulation.scene import Scene, load_scene, parse_scene
    from gimwatch.simulation.simulate import Simulation, run_scene
    from gimwatch.simulation.trajectory import Trajectory
    from gimwatch.stress.reference_planar import PlanarChainReference, planar_reference
    from gimwatch.stress.reference_tree import TreeReference
    from gimwatch.stress.suite import StressResult, run_stress
    from gimwatch.survey.records import RobotFailure, RobotSurvey, SurveyResult
    from gimwatch.survey.report import write_survey
    from gimwatch.survey.run import run_survey
    from gimwatch.watch.watch import Watch

#: Public name -> the module that defines it (imported on first access).
_EXPORTS: dict[str, str] = {
    "BackendWarning": "gimwatch.errors",
    "ExampleRobotWarning": "gimwatch.errors",
    "ChainSpec": "gimwatch.model.chains",
    "ConditioningError": "gimwatch.errors",
    "CrossCheckResult": "gimwatch.crosscheck",
    "DenocModel": "gimwatch.denoc",
    "GimAnalysis": "gimwatch.metrics.dense_analysis",
    "GimwatchError": "gimwatch.errors",
    "GimwatchWarning": "gimwatch.errors",
    "IllConditionedWarning": "gimwatch.errors",
    "InputError": "gimwatch.errors",
    "KappaTracker": "gimwatch.metrics.tracker",
    "TrackerSettings": "gimwatch.metrics.tracker",
    "OutputError": "gimwatch.errors",
    "PlanarChainReference": "gimwatch.stress.reference_planar",
    "Robot": "gimwatch.model.robots",
    "RobotSpec": "gimwatch.model.robot_spec",
    "RobotError": "gimwatch.errors",
    "RobotFailure": "gimwatch.survey.records",
    "RobotSurvey": "gimwatch.survey.records",
    "ScaledDiagonalRatio": "gimwatch.metrics.conditioning",
    "Scene": "gimwatch.simulation.scene",
    "SceneError": "gimwatch.errors",
    "Simulation": "gimwatch.simulation.simulate",
    "SimulationError": "gimwatch.errors",
    "StressResult": "gimwatch.stress.suite",
    "SurveyResult": "gimwatch.survey.records",
    "Trajectory": "gimwatch.simulation.trajectory",
    "TreeReference": "gimwatch.stress.reference_tree",
    "URDFError": "gimwatch.errors",
    "URDFWarning": "gimwatch.errors",
    "Watch": "gimwatch.watch.watch",
    "analyze": "gimwatch.metrics.analyze",
    "analyze_configuration": "gimwatch.metrics.dense_analysis",
    "bundled_scenes": "gimwatch.simulation.bundled_scenes",
    "chain_spec": "gimwatch.model.chains",
    "check_gim": "gimwatch.metrics.conditioning",
    "condition_estimate_1norm": "gimwatch.metrics.conditioning",
    "condition_number": "gimwatch.metrics.conditioning",
    "crosscheck_robot": "gimwatch.crosscheck",
    "diagonal_ratio": "gimwatch.metrics.conditioning",
    "eigenvalues": "gimwatch.metrics.conditioning",
    "estimator_quality": "gimwatch.metrics.estimator_quality",
    "example_robot_names": "gimwatch.model.example_robots",
    "generate_chain_urdf": "gimwatch.model.chains",
    "gim": "gimwatch.model.inertia",
    "gim_diagonal": "gimwatch.model.inertia",
    "ldlt_pivots": "gimwatch.metrics.conditioning",
    "load_robot": "gimwatch.model.robots",
    "default_floating": "gimwatch.model.robot_spec",
    "load_scene": "gimwatch.simulation.scene",
    "neutral_configuration": "gimwatch.model.robots",
    "parse_scene": "gimwatch.simulation.scene",
    "pivot_ratio_backward": "gimwatch.metrics.conditioning",
    "pivot_ratio_forward": "gimwatch.metrics.conditioning",
    "planar_reference": "gimwatch.stress.reference_planar",
    "random_configurations": "gimwatch.model.sampling",
    "run_scene": "gimwatch.simulation.simulate",
    "run_stress": "gimwatch.stress.suite",
    "run_survey": "gimwatch.survey.run",
    "summarize": "gimwatch.simulation.results_folder",
    "TrackedKappa": "gimwatch.metrics.tracker",
    "track_kappa": "gimwatch.metrics.tracker",
    "udut_pivots": "gimwatch.metrics.conditioning",
    "write_chain_urdf": "gimwatch.model.chains",
    "write_simulation": "gimwatch.simulation.results_folder",
    "write_survey": "gimwatch.survey.report",
    "ArmaturePlan": "gimwatch.explain.armature",
    "ConditioningMap": "gimwatch.explain.maps",
    "GimModes": "gimwatch.explain.modes",
    "KappaSensitivities": "gimwatch.explain.sensitivity",
    "Sensitivity": "gimwatch.explain.sensitivity",
    "TrajectoryMetrics": "gimwatch.explain.trajectory",
    "conditioning_map": "gimwatch.explain.maps",
    "gim_modes": "gimwatch.explain.modes",
    "kappa_sensitivities": "gimwatch.explain.sensitivity",
    "minimal_armature": "gimwatch.explain.armature",
    "trajectory_metrics": "gimwatch.explain.trajectory",
}

__all__ = [
    "ArmaturePlan",
    "BackendWarning",
    "ChainSpec",
    "ConditioningError",
    "ConditioningMap",
    "CrossCheckResult",
    "DenocModel",
    "ExampleRobotWarning",
    "GimAnalysis",
    "GimModes",
    "GimwatchError",
    "GimwatchWarning",
    "IllConditionedWarning",
    "InputError",
    "KappaSensitivities",
    "KappaTracker",
    "OutputError",
    "PlanarChainReference",
    "Robot",
    "RobotError",
    "RobotFailure",
    "RobotSpec",
    "RobotSurvey",
    "ScaledDiagonalRatio",
    "Scene",
    "SceneError",
    "Sensitivity",
    "Simulation",
    "SimulationError",
    "StressResult",
    "SurveyResult",
    "TrackedKappa",
    "TrackerSettings",
    "Trajectory",
    "TrajectoryMetrics",
    "TreeReference",
    "URDFError",
    "URDFWarning",
    "Watch",
    "__version__",
    "analyze",
    "analyze_configuration",
    "bundled_scenes",
    "chain_spec",
    "check_gim",
    "condition_estimate_1norm",
    "condition_number",
    "conditioning_map",
    "crosscheck_robot",
    "default_floating",
    "diagonal_ratio",
    "eigenvalues",
    "estimator_quality",
    "example_robot_names",
    "generate_chain_urdf",
    "gim",
    "gim_diagonal",
    "gim_modes",
    "kappa_sensitivities",
    "ldlt_pivots",
    "load_robot",
    "load_scene",
    "minimal_armature",
    "neutral_configuration",
    "parse_scene",
    "pivot_ratio_backward",
    "pivot_ratio_forward",
    "planar_reference",
    "random_configurations",
    "run_scene",
    "run_stress",
    "run_survey",
    "summarize",
    "track_kappa",
    "trajectory_metrics",
    "udut_pivots",
    "write_chain_urdf",
    "write_simulation",
    "write_survey",
]


def __getattr__(name: str) -> Any:
    """Import the module defining ``name`` on first access and cache the name (PEP 562)."""
    module = _EXPORTS.get(name)
    if module is None:
        raise AttributeError(f"module 'gimwatch' has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
