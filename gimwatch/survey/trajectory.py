"""Short simulated trajectories for the survey: does δ track κ along a motion?

For each robot, `TrajectorySettings` ``count`` runs start at rest (v = 0) from the
first random configurations of the survey (samples 1..count) and fall under gravity
g = (0, 0, -9.81) m/s² (URDF's z up; (0, -9.81, 0) for generated chains, which move in
the xy plane) for ``duration_s`` with light diagonal joint damping
c_i = ``damping_per_s`` · M_ii(q0) (each joint alone would lose its velocity at that rate,
whatever its inertia; a constant c would make light distal joints stiff). Joint limits are
not enforced. Each run is an ordinary scene
([`parse_scene`][gimwatch.simulation.scene.parse_scene]) run by
[`gimwatch.simulation.simulate`][gimwatch.simulation.simulate]: DOP853 at a modest tolerance, or
fixed-step RK4 when q has unit-complex coordinates (continuous joints), which SciPy's integrators
cannot integrate as a vector. The watch samples κ, δ and αδ with α = κ(t0)/δ(t0) calibrated at the
first sample of each run (Shah & Saha 2013, Eq. 15, the paper's setting).

Robots with a floating base are not simulated: with gravity as the only effect and no
contact every body falls alike, the joints stay at rest and M(q) does not change.

Per run: Pearson correlation of log δ with log κ, Spearman of δ with κ, and the relative
error |αδ - κ|/κ over the samples after t0. Per robot: the median and minimum correlation
over runs, and the median and maximum error over every sample after t0 of every run.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from gimwatch.errors import InputError
from gimwatch.metrics.estimator_quality import estimator_quality, relative_errors
from gimwatch.model.inertia import gim_diagonal
from gimwatch.model.robots import Robot
from gimwatch.simulation.scene import Scene, parse_scene
from gimwatch.simulation.simulate import Simulation

__all__ = [
    "CHAIN_GRAVITY",
    "GRAVITY",
    "SurveyRun",
    "TrajectorySettings",
    "TrajectoryStatistics",
    "run_trajectory",
    "skip_reason",
    "summarize_runs",
    "trajectory_scene",
]

GRAVITY = (0.0, 0.0, -9.81)
#: Generated chains move in the xy plane (joint axes z): gravity in that plane, as the demo.
CHAIN_GRAVITY = (0.0, -9.81, 0.0)
WATCHED = ("kappa", "diagonal_ratio", "scaled_diagonal_ratio")
FLOATING_REASON = (
    "floating base: under gravity alone with no contact every body falls alike, "
    "the joints stay at rest and M(q) is constant"
)


@dataclass(frozen=True)
class TrajectorySettings:
    """How the survey simulates (see the module docstring).

    Attributes:
        count: Runs per robot, from random samples 1..count.
        duration_s: Length of each run (s).
        sample_s: Interval at which the watch samples κ and δ (s).
        damping_per_s: ζ in c_i = ζ · M_ii(q0) (1/s).
        rtol: Relative tolerance of DOP853.
        atol: Absolute tolerance of DOP853.
        dt_s: Step of RK4 for robots with continuous joints (s).
        max_steps: Integrator steps after which a run is stopped (status ``step-budget``):
            a stiff robot (a light body on a heavy one) would otherwise take hours.
    """

    count: int = 3
    duration_s: float = 1.0
    sample_s: float = 0.02
    damping_per_s: float = 0.5
    rtol: float = 1e-6
    atol: float = 1e-8
    dt_s: float = 1e-3
    max_steps: int = 5000

    def __post_init__(self) -> None:
        for name in ("count", "max_steps"):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or value < 1:
                raise InputError(name, "a positive integer", value)
        for name in ("duration_s", "sample_s", "damping_per_s", "rtol", "atol", "dt_s"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise InputError(name, "a finite number >= 0", value)
        if self.duration_s <= 0 or self.sample_s <= 0 or self.dt_s <= 0:
            raise InputError("duration", "> 0 s", self.duration_s)
        if self.sample_s > self.duration_s:
            raise InputError("sample_s", f"<= the duration ({self.duration_s} s)", self.sample_s)

    def record(self) -> dict:
        """JSON-ready settings, with the formulas in words."""
        return {
            "runs_per_robot": self.count,
            "start": "random samples 1..runs_per_robot, at rest",
            "duration_s": self.duration_s,
            "sample_s": self.sample_s,
            "gravity_m_s2": list(GRAVITY),
            "gravity_m_s2_generated_chains": list(CHAIN_GRAVITY),
            "damping": f"c_i = {self.damping_per_s} /s * M_ii(q0)",
            "integrator": f"DOP853 rtol {self.rtol:g} atol {self.atol:g}; "
            f"RK4 dt {self.dt_s:g} s with continuous joints",
            "max_steps": self.max_steps,
            "calibration": "alpha = kappa/delta at t0 of each run",
        }


def skip_reason(robot: Robot) -> str:
    """Why a robot's trajectories are not simulated, or "" when they are."""
    return FLOATING_REASON if robot.floating else ""


def trajectory_scene(robot: Robot, q0: np.ndarray, settings: TrajectorySettings) -> Scene:
    """The scene of one run: ``robot`` falling from rest at ``q0`` under light damping."""
    damping = settings.damping_per_s * gim_diagonal(robot, q0)
    if robot.nq == robot.nv:
        integrator = {"method": "DOP853", "rtol": settings.rtol, "atol": settings.atol}
    else:
        integrator = {"method": "RK4", "dt": settings.dt_s}
    table = {
        "robot": robot.spec,
        "base": "floating" if robot.free_base else "fixed",
        "q": [float(x) for x in q0],
        "duration": settings.duration_s,
        "sample": settings.sample_s,
        "effects": {
            "gravity": {"vector": list(CHAIN_GRAVITY if robot.chain else GRAVITY)},
            "damping": {"coefficient": [float(c) for c in damping]},
        },
        "integrator": integrator,
        "watch": {"metrics": list(WATCHED)},
    }
    return parse_scene(table, source=f"<survey trajectory of {robot.name}>")


@dataclass(frozen=True)
class SurveyRun:
    """One simulated run and how δ tracked κ along it.

    Attributes:
        start_sample: The random sample it started from.
        status: `gimwatch.simulation.simulate.STATUSES`; only completed runs enter the
        statistics.
        message: Why it stopped early ("" when completed).
        method: Integrator used.
        steps: Integrator steps taken.
        t: Watch sample times (s).
        q: Configurations at the samples, shape (len(t), nq).
        kappa: κ at the samples.
        diagonal_ratio: δ at the samples.
        scaled_diagonal_ratio: αδ at the samples (α at t0).
        alpha: κ(t0)/δ(t0).
        pearson_log: Pearson correlation of log δ with log κ (NaN if either is constant).
        spearman: Spearman correlation of δ with κ (NaN if either is constant).
        alpha_delta_rel_error_median: median |αδ - κ|/κ after t0.
        alpha_delta_rel_error_max: max |αδ - κ|/κ after t0.
    """

    start_sample: int
    status: str
    message: str
    method: str
    steps: int
    t: np.ndarray = field(repr=False)
    q: np.ndarray = field(repr=False)
    kappa: np.ndarray = field(repr=False)
    diagonal_ratio: np.ndarray = field(repr=False)
    scaled_diagonal_ratio: np.ndarray = field(repr=False)
    alpha: float
    pearson_log: float
    spearman: float
    alpha_delta_rel_error_median: float
    alpha_delta_rel_error_max: float

    @property
    def kappa_spread(self) -> float:
        """The ratio max κ / min κ along the run: how much there was to track."""
        return float(self.kappa.max() / self.kappa.min()) if self.kappa.size else math.nan


def run_trajectory(
    robot: Robot, q0: np.ndarray, start_sample: int, settings: TrajectorySettings
) -> SurveyRun:
    """Simulate one run and measure how δ tracks κ along it.

    Raises:
        GimwatchError: The scene cannot be built (e.g. a singular M(q0)).
    """
    simulation = Simulation(trajectory_scene(robot, q0, settings))
    steps = 0

    def budget(_: float) -> str | None:
        """Stop the run (by returning a message) once it has taken max_steps steps."""
        nonlocal steps
        steps += 1
        return "step budget" if steps >= settings.max_steps else None

    trajectory = simulation.run(progress=budget)
    status, message = trajectory.status, trajectory.message
    if status == "interrupted":
        raise KeyboardInterrupt  # the user's Ctrl-C: stop the survey, not just this run
    if status == "stopped":
        status = "step-budget"
        message = f"stopped after {steps} steps at t = {trajectory.t[-1]:.3g} s (stiff)"
    watch = trajectory.watch
    kappa, delta = watch["watch_kappa"], watch["watch_diagonal_ratio"]
    alpha_delta = watch["watch_scaled_diagonal_ratio"]
    quality = estimator_quality(kappa, delta)
    return SurveyRun(
        start_sample=start_sample,
        status=status,
        message=message,
        method=trajectory.scene.integrator.method,
        steps=trajectory.steps,
        t=trajectory.t[: kappa.size],
        q=trajectory.q[: kappa.size],
        kappa=kappa,
        diagonal_ratio=delta,
        scaled_diagonal_ratio=alpha_delta,
        alpha=math.nan if trajectory.alpha is None else float(trajectory.alpha),
        pearson_log=math.nan if quality is None else quality.pearson_log,
        spearman=math.nan if quality is None else quality.spearman,
        alpha_delta_rel_error_median=math.nan if quality is None else quality.median_relative_error,
        alpha_delta_rel_error_max=math.nan if quality is None else quality.max_relative_error,
    )


@dataclass(frozen=True)
class TrajectoryStatistics:
    """A robot's runs and how δ tracked κ along them.

    Attributes:
        runs: The runs, by start sample; empty when skipped.
        skipped: Why no run was simulated ("" when they were).
        errors: Runs that could not be simulated: (start sample, reason).
        pearson_log_median: Median over completed runs of Pearson r(log δ, log κ).
        pearson_log_min: Smallest of those.
        spearman_median: Median over completed runs of the Spearman correlation.
        alpha_delta_rel_error_median: median |αδ - κ|/κ over every sample after t0.
        alpha_delta_rel_error_max: max |αδ - κ|/κ over those samples.
        kappa_spread_median: Median over runs of max κ / min κ along the run.
    """

    runs: tuple[SurveyRun, ...] = ()
    skipped: str = ""
    errors: tuple[tuple[int, str], ...] = ()
    pearson_log_median: float = math.nan
    pearson_log_min: float = math.nan
    spearman_median: float = math.nan
    alpha_delta_rel_error_median: float = math.nan
    alpha_delta_rel_error_max: float = math.nan
    kappa_spread_median: float = math.nan

    @property
    def completed(self) -> tuple[SurveyRun, ...]:
        """The runs that reached their duration."""
        return tuple(run for run in self.runs if run.status == "completed")


def _nan_stat(function, values: Sequence[float]) -> float:
    finite = np.array([v for v in values if math.isfinite(v)])
    return float(function(finite)) if finite.size else math.nan


def summarize_runs(
    runs: Sequence[SurveyRun], errors: Sequence[tuple[int, str]] = ()
) -> TrajectoryStatistics:
    """Per-robot statistics over the completed runs (see the module docstring)."""
    done = [run for run in runs if run.status == "completed"]
    errors_per_run = [relative_errors(r.kappa, r.scaled_diagonal_ratio) for r in done]
    error = np.concatenate(errors_per_run) if errors_per_run else np.empty(0)
    return TrajectoryStatistics(
        runs=tuple(runs),
        errors=tuple(errors),
        pearson_log_median=_nan_stat(np.median, [r.pearson_log for r in done]),
        pearson_log_min=_nan_stat(np.min, [r.pearson_log for r in done]),
        spearman_median=_nan_stat(np.median, [r.spearman for r in done]),
        alpha_delta_rel_error_median=float(np.median(error)) if error.size else math.nan,
        alpha_delta_rel_error_max=float(np.max(error)) if error.size else math.nan,
        kappa_spread_median=_nan_stat(np.median, [r.kappa_spread for r in done]),
    )
