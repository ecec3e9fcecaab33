"""gimwatch: watch the conditioning of a robot's generalized inertia matrix (GIM).

Importing gimwatch does no work: no robot is loaded and nothing is written.
"""

from gimwatch._version import __version__
from gimwatch.crosscheck import CrossCheckResult, crosscheck_robot
from gimwatch.denoc import DenocModel
from gimwatch.errors import (
    ConditioningError,
    GimwatchError,
    IllConditionedWarning,
    InputError,
    RobotError,
    SceneError,
    SimulationError,
    URDFError,
)
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
from gimwatch.metrics.matrix_free import (
    MatrixFreeKappa,
    gim_inverse_operator,
    gim_operator,
    kappa_matrix_free,
)
from gimwatch.metrics.watch import Watch, estimator_quality
from gimwatch.model.chains import ChainSpec, chain_spec, generate_chain_urdf, write_chain_urdf
from gimwatch.model.inertia import gim, gim_diagonal
from gimwatch.model.robots import (
    Robot,
    example_robot_names,
    load_robot,
    neutral_configuration,
    random_configurations,
)
from gimwatch.simulation.results_folder import summarize, write_simulation
from gimwatch.simulation.scene import Scene, load_scene, parse_scene
from gimwatch.simulation.simulate import Simulation, Trajectory, run_scene
from gimwatch.stress.reference_planar import PlanarChainReference, planar_reference
from gimwatch.stress.reference_tree import TreeReference
from gimwatch.stress.suite import StressResult, run_stress
from gimwatch.survey.report import write_survey
from gimwatch.survey.run import RobotFailure, RobotSurvey, SurveyResult, run_survey

__all__ = [
    "ChainSpec",
    "ConditioningError",
    "CrossCheckResult",
    "DenocModel",
    "GimAnalysis",
    "GimwatchError",
    "IllConditionedWarning",
    "InputError",
    "MatrixFreeKappa",
    "PlanarChainReference",
    "Robot",
    "RobotError",
    "RobotFailure",
    "RobotSurvey",
    "ScaledDiagonalRatio",
    "Scene",
    "SceneError",
    "Simulation",
    "SimulationError",
    "StressResult",
    "SurveyResult",
    "Trajectory",
    "TreeReference",
    "URDFError",
    "Watch",
    "__version__",
    "analyze_configuration",
    "chain_spec",
    "check_gim",
    "condition_estimate_1norm",
    "condition_number",
    "crosscheck_robot",
    "diagonal_ratio",
    "eigenvalues",
    "estimator_quality",
    "example_robot_names",
    "generate_chain_urdf",
    "gim",
    "gim_diagonal",
    "gim_inverse_operator",
    "gim_operator",
    "kappa_matrix_free",
    "ldlt_pivots",
    "load_robot",
    "load_scene",
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
    "udut_pivots",
    "write_chain_urdf",
    "write_simulation",
    "write_survey",
]
