"""Survey robots: does the diagonal ratio track κ, and what makes M(q) ill-conditioned?

For each robot, sample 0 is the neutral configuration (Pinocchio's ``neutral``: zero angles,
identity quaternions) and samples 1..K are drawn uniformly within the joint limits with
[`random_configurations`][gimwatch.model.sampling.random_configurations] (seeded, all drawn up
front, then cut into chunks), so the result does not depend on how the chunks are scheduled.
At every sample the GIM M(q) comes from Pinocchio's CRBA and gives:

* κ₂ = λmax/λmin (Shah & Saha 2013, Eq. 6) and δ = max M_ii / min M_ii (Sec. 4);
* the forward (LDLᵀ) and backward (UDUᵀ) pivot ratios (Sec. 4, Fig. 4);
* the coordinates holding the largest and smallest diagonal entries, and the coordinate
  with the largest weight |v_k| in the eigenvectors of λmin and λmax.

Per robot the survey reports quantiles of κ, δ and the pivot ratios; the Pearson and
Spearman correlations of log δ with log κ; the relative error |αδ - κ|/κ of the scaled
diagonal ratio (Eq. 15) with α = κ/δ calibrated once at the neutral sample (the paper's
t0), over samples 1..K; the worst configurations; and the coordinates that most often
carry the extremes. Nothing here prints; [`gimwatch.survey.report`][gimwatch.survey.report] writes
the files.
"""

from __future__ import annotations

import threading
from collections import Counter
from collections.abc import Callable, Sequence
from dataclasses import replace
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING, TypedDict, Unpack

import numpy as np

from gimwatch.errors import ConditioningError, GimwatchError, InputError, RobotError
from gimwatch.metrics.conditioning import warn_if_ill_conditioned
from gimwatch.metrics.dense_analysis import check_robot_gim
from gimwatch.metrics.estimator_quality import correlations, estimator_quality
from gimwatch.metrics.mass_matrix_sources import PinocchioSource
from gimwatch.metrics.registry import GimState, evaluate
from gimwatch.model.example_robots import example_robot_names
from gimwatch.model.inertia import gim
from gimwatch.model.robots import Robot, load_robot, neutral_configuration
from gimwatch.model.sampling import placeholder_limit_joints
from gimwatch.model.sampling import random_configurations as _random_configurations
from gimwatch.survey.records import RobotFailure, RobotSurvey, SurveyResult, WorstConfiguration
from gimwatch.survey.sweep import SweepOutcome, Task, run_sweep
from gimwatch.survey.trajectory import (
    TrajectorySettings,
    TrajectoryStatistics,
    run_trajectory,
    skip_reason,
    summarize_runs,
)

__all__ = [
    "QUANTILES",
    "RobotFailure",
    "RobotSurvey",
    "SurveyResult",
    "SweepOptions",
    "WorstConfiguration",
    "run_survey",
    "sample_metrics",
    "survey_robot_specs",
]

#: Quantile levels reported for κ, δ and the pivot ratios.
QUANTILES = {"min": 0.0, "p05": 0.05, "median": 0.5, "p95": 0.95, "max": 1.0}
#: The registry metrics among the per-sample metrics (the registry's names are the column names).
SURVEY_METRICS = (
    "kappa",
    "diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "kappa_equilibrated",
)
#: Per-sample metrics, in the order of the CSV columns.
METRICS = (*SURVEY_METRICS, "lambda_min", "lambda_max")
#: Per-sample coordinate indices (into ``Robot.dof_names``).
DOF_METRICS = ("max_diagonal_dof", "min_diagonal_dof", "lambda_min_dof", "lambda_max_dof")
_NO_DOF = "has no degree of freedom"
WORST_COUNT = 3

if TYPE_CHECKING:
    pass


#: Estimated in-process cost of one sample (CRBA, eigh, two factorisations), in seconds: a
#: constant for the Python around it plus the O(nv³) eigensolve. Only decides whether a
#: default sweep starts worker processes (`gimwatch.survey.sweep.POOL_WORTH_S`).
SAMPLE_COST_S, SAMPLE_COST_S_PER_NV3 = 2e-3, 6e-9
#: Estimated in-process cost of one simulated run, per simulated second.
RUN_COST_S_PER_S = 1.0


def _sample_cost_s(nv: int) -> float:
    return SAMPLE_COST_S + SAMPLE_COST_S_PER_NV3 * nv**3


def survey_robot_specs(specs: Sequence[str]) -> list[str]:
    """Expand ``all`` into every example-robot-data name and drop repeats, keeping order."""
    expanded: list[str] = []
    for spec in specs:
        names = example_robot_names() if spec == "all" else (spec,)
        expanded += [name for name in names if name not in expanded]
    return expanded


def sample_metrics(robot: Robot, qs: np.ndarray, *, data=None) -> dict[str, np.ndarray]:
    """κ, δ, pivot ratios, extreme eigenvalues and extreme coordinates at each row of ``qs``.

    Returns:
        Arrays of length ``len(qs)`` keyed by `METRICS` (floats) and
        `DOF_METRICS` (int indices into ``robot.dof_names``).

    Raises:
        ConditioningError: M(q) is singular (a coordinate moves no mass) or not positive definite.
    """
    data = robot.new_data() if data is None else data
    out = {key: np.empty(len(qs)) for key in METRICS}
    out |= {key: np.empty(len(qs), dtype=np.int64) for key in DOF_METRICS}
    for row, q in enumerate(qs):
        M = check_robot_gim(robot, gim(robot, q, data=data))
        state = GimState(PinocchioSource(robot, data), q, full=True, matrix=M)
        spectrum, vectors = state.eigenpairs  # one eigh: the spectrum and the extreme modes
        if spectrum[0] <= 0:
            raise ConditioningError(
                f"M(q) of {robot.name} is not positive definite (λmin = {spectrum[0]:.3g})"
            )
        for name, value in evaluate(SURVEY_METRICS, state).items():
            out[name][row] = value
        out["lambda_min"][row], out["lambda_max"][row] = state.extremes
        out["max_diagonal_dof"][row] = np.argmax(state.diag)
        out["min_diagonal_dof"][row] = np.argmin(state.diag)
        out["lambda_min_dof"][row] = np.argmax(np.abs(vectors[:, 0]))
        out["lambda_max_dof"][row] = np.argmax(np.abs(vectors[:, -1]))
    return out


@lru_cache(maxsize=16)
def _worker_robot(spec: str, floating: bool, thread: int):
    robot = load_robot(spec, floating=floating)
    return robot, robot.new_data()  # one Data per thread: Pinocchio's Data is not shared


def _survey_chunk(spec: str, floating: bool, qs: np.ndarray) -> dict | str:
    """Worker entry point: metrics of one chunk, or the error message of a bad robot."""
    try:
        robot, data = _worker_robot(spec, floating, threading.get_ident())
        return sample_metrics(robot, qs, data=data)
    except GimwatchError as exc:
        return str(exc)


def _trajectory_task(spec: str, floating: bool, q0: np.ndarray, start: int, settings):
    """Worker entry point: one simulated run (a ``SurveyRun``), or why it could not run."""
    try:
        robot, _ = _worker_robot(spec, floating, threading.get_ident())
        return run_trajectory(robot, q0, start, settings)
    except GimwatchError as exc:
        return str(exc)


def _summarize(robot: Robot, note: str, index: np.ndarray, metrics, qs) -> RobotSurvey:
    kappa, delta = metrics["kappa"], metrics["diagonal_ratio"]
    # t0 is the neutral configuration; without it (its M was refused) there is no α
    quality = estimator_quality(kappa, delta) if index[0] == 0 else None
    pearson, spearman = correlations(delta, kappa)
    # δ and κ_S split κ (κ ≤ δ·κ_S) into the diagonal's spread and the coupling: whether they
    # move together is a property of the robot, not of δ
    pearson_s, _ = correlations(delta, metrics["kappa_equilibrated"])
    nan = float("nan")
    quantiles = {
        key: {name: float(np.quantile(metrics[key], level)) for name, level in QUANTILES.items()}
        for key in SURVEY_METRICS
    }
    order = np.argsort(-kappa, kind="stable")[:WORST_COUNT]
    worst = tuple(
        WorstConfiguration(
            sample=int(index[k]),
            kappa=float(kappa[k]),
            diagonal_ratio=float(delta[k]),
            q=tuple(float(x) for x in qs[index[k]]),
        )
        for k in order
    )
    extreme = {}
    for key in DOF_METRICS:
        dof, count = Counter(metrics[key].tolist()).most_common(1)[0]
        extreme[key] = (robot.dof_names[dof], count / index.size)
    aligned = float(np.mean(metrics["lambda_min_dof"] == metrics["min_diagonal_dof"]))
    return RobotSurvey(
        name=robot.name,
        spec=robot.spec,
        nv=robot.nv,
        floating=robot.free_base,  # an MJCF file may float its robot itself
        note=note,
        dof_names=robot.dof_names,
        sample_index=index,
        metrics=metrics,
        alpha=nan if quality is None else quality.alpha,
        quantiles=quantiles,
        pearson_log=pearson,
        spearman=spearman,
        pearson_log_delta_kappa_equilibrated=pearson_s,
        alpha_delta_rel_error_median=nan if quality is None else quality.median_relative_error,
        alpha_delta_rel_error_max=nan if quality is None else quality.max_relative_error,
        worst=worst,
        extreme_dofs=extreme,
        lambda_min_on_min_diagonal=aligned,
        placeholder_limits=placeholder_limit_joints(robot),
    )


def _load(spec: str, floating: bool | None) -> tuple[Robot, str]:
    try:
        return load_robot(spec, floating=floating), ""
    except RobotError as exc:
        if floating or not exc.problem.startswith(_NO_DOF):
            raise
    note = "no joint with a fixed base: surveyed with a free-flyer base"
    return load_robot(spec, floating=True), note


def _worker_spec(spec: str) -> str:
    """Specs as workers must see them: URDF paths made absolute (workers may run elsewhere)."""
    path = Path(spec)
    if spec.lower().endswith((".urdf", ".xml")) and path.exists():
        return str(path.resolve())
    return spec


#: Samples per task when the caller names no ``chunk_size``.
DEFAULT_CHUNK_SIZE = 50


class SweepOptions(TypedDict, total=False):
    """How a survey's chunks run: the keyword options `run_survey` passes to its sweep."""

    chunk_size: int
    workers: int | None
    scheduler: str | None
    progress: Callable[[int, int], None] | None


def run_survey(
    specs: Sequence[str],
    *,
    samples: int = 200,
    seed: int = 0,
    floating: bool | None = None,
    trajectories: TrajectorySettings | None = None,
    **sweep: Unpack[SweepOptions],
) -> SurveyResult:
    """Survey robots at the neutral configuration plus ``samples`` random ones each.

    Robots that cannot be loaded, or whose M(q) is singular, become
    [`RobotFailure`][gimwatch.survey.run.RobotFailure] records and the survey goes on. Ctrl-C
    returns what was finished (``interrupted=True``).

    Args:
        specs: Robot specifications; ``all`` means every example-robot-data robot.
        samples: K, random configurations per robot (>= 1), besides the neutral one.
        seed: Seed of [`random_configurations`][gimwatch.model.sampling.random_configurations] (same
            for every robot).
        floating: True gives every robot a free-flyer base, False a fixed one; None (the
            default) each robot its own (`default_floating`: example-robot-data's base,
            a free-flyer for legged robots and humanoids). A robot with no joint on a fixed base
            (a drone) gets a free-flyer anyway and says so in ``note``.
        trajectories: Also simulate short runs from random samples 1..count of each robot
            (`gimwatch.survey.trajectory`); each run is one more task of the sweep.
        **sweep: How the chunks run (`SweepOptions`): ``chunk_size`` (samples per task,
            default 50); ``workers`` (local processes; 1 runs in this process; default: this
            process for small surveys, estimated under a few seconds, else every core);
            ``scheduler`` (``"local"`` or a Dask scheduler address to run the chunks on
            Dask); ``progress`` (called as ``progress(finished_chunks, total_chunks)`` after
            each chunk).
    """
    chunk_size = sweep.get("chunk_size", DEFAULT_CHUNK_SIZE)
    for name, value in (("samples", samples), ("chunk_size", chunk_size)):
        if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < 1:
            raise InputError(name, "a positive integer", value)
    failures: list[RobotFailure] = []
    loaded = _load_robots(survey_robot_specs(specs), floating, samples, seed, failures)
    runs_wanted = 0 if trajectories is None else min(trajectories.count, samples)
    tasks, owners = _survey_tasks(loaded, chunk_size, runs_wanted, trajectories)
    finished = 0
    progress = sweep.get("progress")

    def chunk_done(_: int) -> None:
        nonlocal finished
        finished += 1
        if progress is not None:
            progress(finished, len(tasks))

    outcome = run_sweep(
        tasks, workers=sweep.get("workers"), scheduler=sweep.get("scheduler"), progress=chunk_done
    )
    robots, not_reached = _robot_surveys(loaded, outcome, owners, trajectories, failures)
    return SurveyResult(
        robots=tuple(robots),
        failures=tuple(failures),
        samples=samples,
        seed=seed,
        interrupted=outcome.interrupted,
        not_reached=tuple(not_reached),
        trajectory_settings=trajectories,
    )


#: One loaded robot of a survey: the robot, its note and its samples (neutral first).
_Loaded = tuple[Robot, str, np.ndarray]


def _load_robots(
    specs: Sequence[str],
    floating: bool | None,
    samples: int,
    seed: int,
    failures: list[RobotFailure],
) -> list[_Loaded]:
    """Each robot that loads, with its samples; the others appended to ``failures``."""
    loaded: list[_Loaded] = []
    for spec in specs:
        try:
            robot, note = _load(spec, floating)
        except GimwatchError as exc:
            failures.append(RobotFailure(spec=spec, stage="load", reason=str(exc)))
            continue
        qs = np.vstack(
            [neutral_configuration(robot), _random_configurations(robot, samples, seed=seed)]
        )
        loaded.append((robot, note, qs))
    return loaded


def _survey_tasks(
    loaded: list[_Loaded],
    chunk_size: int,
    runs_wanted: int,
    trajectories: TrajectorySettings | None,
) -> tuple[list[Task], list[tuple[int, int]]]:
    """The sweep's tasks (chunks, then runs) and each one's owner (robot, first sample).

    A run's owner carries minus the sample it starts from.
    """
    tasks, owners = [], []
    for k, (robot, _, qs) in enumerate(loaded):
        for start in range(0, len(qs), chunk_size):
            chunk = qs[start : start + chunk_size]
            args: tuple = (_worker_spec(robot.spec), robot.floating, chunk)
            tasks.append(Task(_survey_chunk, args, cost_s=len(chunk) * _sample_cost_s(robot.nv)))
            owners.append((k, start))
    for k, (robot, _, qs) in enumerate(loaded):
        if trajectories is None or runs_wanted == 0 or skip_reason(robot):
            continue
        for start in range(1, 1 + runs_wanted):
            args = (_worker_spec(robot.spec), robot.floating, qs[start], start, trajectories)
            tasks.append(
                Task(_trajectory_task, args, cost_s=RUN_COST_S_PER_S * trajectories.duration_s)
            )
            owners.append((k, -start))  # negative: a run from that sample
    return tasks, owners


def _robot_surveys(
    loaded: list[_Loaded],
    outcome: SweepOutcome,
    owners: list[tuple[int, int]],
    trajectories: TrajectorySettings | None,
    failures: list[RobotFailure],
) -> tuple[list[RobotSurvey], list[str]]:
    """Each robot's survey from its chunks and runs; robots with a failed chunk in ``failures``.

    Also the specs of robots no chunk of which finished (an interrupted survey).
    """
    by_robot: dict[int, list] = {k: [] for k in range(len(loaded))}
    runs: dict[int, list] = {k: [] for k in range(len(loaded))}
    for i in sorted(outcome.results):  # task order: robot by robot, chunks ascending
        k, start = owners[i]
        (by_robot[k] if start >= 0 else runs[k]).append((start, outcome.results[i]))
    robots, not_reached = [], []
    for k, (robot, note, qs) in enumerate(loaded):
        parts = by_robot[k]
        errors = [part for _, part in parts if isinstance(part, str)]
        if errors:
            failures.append(RobotFailure(spec=robot.spec, stage="gim", reason=errors[0]))
            continue
        if not parts:
            not_reached.append(robot.spec)
            continue
        index = np.concatenate([np.arange(s, s + len(p["kappa"])) for s, p in parts])
        metrics = {key: np.concatenate([p[key] for _, p in parts]) for key in parts[0][1]}
        summary = _summarize(robot, note, index, metrics, qs)
        warn_if_ill_conditioned(
            float(np.max(metrics["kappa"])), where=f"{robot.name} (largest over its samples)"
        )
        if trajectories is not None:
            summary = replace(summary, trajectories=_trajectory_statistics(robot, runs[k]))
        robots.append(summary)
    return robots, not_reached


def _trajectory_statistics(robot: Robot, parts: list) -> TrajectoryStatistics:
    if skip_reason(robot):
        return TrajectoryStatistics(skipped=skip_reason(robot))
    done = [part for _, part in parts if not isinstance(part, str)]
    errors = [(-start, part) for start, part in parts if isinstance(part, str)]
    return summarize_runs(done, errors)
