"""Conditioning maps: κ, δ or any scalar registry metric over a grid of two joints, or along a path.

A map fixes every joint but two at a base configuration and sweeps those two over a grid.
The grid is cut into row chunks, each a `Task`, so that a large
map runs in this process, on local processes or on a Dask cluster (the survey's
`run_sweep`), shows progress chunk by chunk, and keeps the
finished rows when interrupted (the others are NaN). Two paths, as ``analyze``:

* dense (``crba``): Pinocchio's CRBA per point; κ and δ of a chunk from one batched
  eigen-solve / diagonal read, other scalar metrics through the registry on the formed M;
* O(n) (``denoc``, chains beyond Pinocchio's Data, or asked for): DeNOC's linear-time state
  per point (`gimwatch.metrics.linear_analysis.analyze_linear`, no M formed) for δ and
  the backward pivot ratio, and κ by the κ tracker (`gimwatch.metrics.tracker`,
  warm-started Lanczos, relative tolerance 1e-10 per end) along the chunk's points, visited
  in serpentine order so that each starts from its neighbour's eigenvectors.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import TypedDict, Unpack

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.joint_kinds import JointKind, joint_kind
from gimwatch.metrics.analyze import RobotLike, choose_path, robot_for_path, spec_of
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.metrics.dense_analysis import check_massless
from gimwatch.metrics.linear_analysis import LINEAR_METRICS
from gimwatch.metrics.registry import METRICS, GimState, evaluate
from gimwatch.model.q_checks import as_configurations
from gimwatch.model.robot_spec import RobotSpec, robot_spec
from gimwatch.model.robots import DATA_NV_LIMIT, load_robot
from gimwatch.model.sampling import is_real_limit
from gimwatch.suggest import did_you_mean
from gimwatch.survey.sweep import Task, run_sweep
from gimwatch.watch.sources import GivenMatrix

__all__ = [
    "CHUNK_POINTS",
    "MAX_GRID",
    "ConditioningMap",
    "Execution",
    "check_metrics",
    "conditioning_map",
    "map_axes",
    "metrics_at",
    "robot_coordinates",
    "run_chunks",
    "scalar_metrics",
]

#: Points per side of a map at most (a 2,000 × 2,000 map is 4 million configurations).
MAX_GRID = 2000
#: Configurations per chunk of work (rows are grouped up to about this many points).
CHUNK_POINTS = 4000
#: The most memory the dense matrices M(q) of one block of configurations take (float64).
MATRIX_BLOCK_BYTES = 256 << 20


def scalar_metrics(path: str) -> tuple[str, ...]:
    """The metrics a map can hold on ``path``: scalar registry metrics (dense), or O(n) ones."""
    if path == "denoc":
        return LINEAR_METRICS
    return tuple(name for name, cls in METRICS.items() if not cls.vector)


def check_metrics(metrics: Sequence[str], path: str) -> tuple[str, ...]:
    """``metrics`` if each is a map metric of ``path``, else an InputError naming it."""
    allowed = scalar_metrics(path)
    for name in metrics:
        if name not in allowed:
            hint = did_you_mean(name, allowed).removeprefix("; ")
            raise InputError(
                "metrics", f"among {', '.join(allowed)} on the {path} path", name, hint=hint
            )
    if not metrics:
        raise InputError("metrics", "at least one metric", list(metrics))
    return tuple(metrics)


def _robot(spec: RobotSpec):
    """The dense path's robot: the one choose_path read or the caller gave (loaded once)."""
    chain = spec.chain
    if chain is not None and chain.n + 6 * spec.floating > DATA_NV_LIMIT:
        return load_robot(spec, max_nv=DATA_NV_LIMIT)  # refused, naming the O(n) path
    return robot_for_path(spec)


@functools.lru_cache(maxsize=2)
def _linear_model(spec: RobotSpec):
    from gimwatch.denoc import DenocModel

    chain = spec.chain
    if chain is not None:
        return DenocModel.from_chain(chain), chain.name
    robot = _file_robot(spec)
    return denoc_model(robot), robot.name


@functools.lru_cache(maxsize=2)
def _file_robot(spec: RobotSpec):
    """A file's robot for the O(n) path: its Pinocchio Model, never a Data (any nv)."""
    return robot_for_path(spec)


@functools.lru_cache(maxsize=2)
def _lean(spec: RobotSpec):
    return _linear_model(spec)[0].lean()


def robot_coordinates(spec: RobotSpec | str, path: str) -> tuple[str, list[str]]:
    """(robot name, names of the q coordinates in order) on ``path``."""
    spec = robot_spec(spec)  # a RobotSpec as given, a caller's text parsed
    if path == "denoc" and spec.chain is not None:
        model, name = _linear_model(spec)
        return name, list(model.joint_names)
    from gimwatch.output.figures import joint_coordinate_units

    robot = _robot(spec) if path == "crba" else _file_robot(spec)
    return robot.name, joint_coordinate_units(robot.model)[0]


def metrics_at(
    spec: RobotSpec | str, path: str, qs: np.ndarray, metrics: tuple[str, ...]
) -> np.ndarray:
    """The metrics at each configuration of ``qs`` (K, nq): an array (len(metrics), K).

    Module-level and keyed by ``spec`` so that it can run in worker processes.
    """
    spec = robot_spec(spec)  # a RobotSpec as given, a caller's text parsed
    out = np.full((len(metrics), len(qs)), np.nan)
    if path == "denoc":
        from gimwatch.metrics.linear_analysis import analyze_linear
        from gimwatch.metrics.tracker import track_kappa

        model, name = _linear_model(spec)
        others = tuple(m for m in metrics if m != "kappa") or ("diagonal_ratio",)
        for k, q in enumerate(qs):  # δ always: it checks that every coordinate moves mass
            record = analyze_linear(model, q, name=name, metrics=others)
            for i, metric in enumerate(metrics):
                if metric != "kappa":
                    out[i, k] = getattr(record, metric)
        if "kappa" in metrics:  # warm-started from point to point, O(n) each (metrics/tracker)
            out[metrics.index("kappa")] = [s.kappa for s in track_kappa(_lean(spec), qs)]
        return out
    robot = _robot(spec)
    data = robot.new_data()
    # K dense matrices at once: at most MATRIX_BLOCK_BYTES of them (a 4,000-point chunk of
    # a 400-DoF robot would hold 5 GB)
    block = max(1, MATRIX_BLOCK_BYTES // (8 * robot.nv**2))
    for start in range(0, len(qs), block):
        part = slice(start, start + block)
        out[:, part] = _dense_metrics(robot, data, qs[part], metrics)
    return out


def _dense_metrics(robot, data, qs: np.ndarray, metrics: tuple[str, ...]) -> np.ndarray:
    """The metrics at ``qs`` from Pinocchio's dense M, all of the block's M held at once."""
    out = np.full((len(metrics), len(qs)), np.nan)
    Ms = np.array([pin.crba(robot.model, data, q) for q in qs])
    diagonal = np.diagonal(Ms, axis1=1, axis2=2)
    for row in diagonal[np.any(~(diagonal > 0), axis=1)][:1]:  # M singular: say which joints
        check_massless(row, robot.dof_names, name=robot.name, source=robot.source)
    rest = []
    for i, metric in enumerate(metrics):
        if metric == "kappa":
            w = np.linalg.eigvalsh(Ms)
            out[i] = w[:, -1] / w[:, 0]
        elif metric == "diagonal_ratio":
            diag = np.diagonal(Ms, axis1=1, axis2=2)
            out[i] = diag.max(axis=1) / diag.min(axis=1)
        else:
            rest.append(i)
    if rest:
        names = [metrics[i] for i in rest]
        instances: dict = {}
        for k, M in enumerate(Ms):
            values = evaluate(names, GimState(GivenMatrix(len(M)), full=True, matrix=M), instances)
            out[rest, k] = [values[name] for name in names]
    return out


@dataclass(frozen=True)
class ConditioningMap:
    """Metrics over a grid of two joints (rows: the second joint, columns: the first).

    Attributes:
        robot: Robot name.
        joints: The two joints swept (x, y).
        units: Their units (rad or m).
        x: Values of the first joint, length nx.
        y: Values of the second joint, length ny.
        base_q: The configuration the other joints keep.
        path: ``crba`` or ``denoc``.
        values: Metric name -> array (ny, nx); NaN where an interruption left points undone.
        interrupted: Whether Ctrl-C stopped the map early.
    """

    robot: str
    joints: tuple[str, str]
    units: tuple[str, str]
    x: np.ndarray
    y: np.ndarray
    base_q: np.ndarray
    path: str
    values: dict[str, np.ndarray]
    interrupted: bool = False


def checked_configurations(
    spec: RobotSpec | str, path: str, qs: np.ndarray, *, name: str = "q"
) -> np.ndarray:
    """``qs`` (K, nq) checked as every q is checked (`gimwatch.model.q_checks`).

    Length and finiteness; on Pinocchio's path each (cos θ, sin θ) and quaternion of norm 1
    too (DeNOC's q are angles, without unit blocks).
    """
    spec = robot_spec(spec)  # a RobotSpec as given, a caller's text parsed
    if path != "denoc":
        return as_configurations(_robot(spec), qs, name=name)
    size = len(_linear_model(spec)[0].joint_names)
    if qs.ndim != 2 or qs.shape[1] != size or not np.all(np.isfinite(qs)):
        raise InputError(name, f"rows of {size} finite numbers", qs.shape)
    return qs


def map_axes(
    spec: RobotSpec | str, path: str, joints: Sequence[str]
) -> tuple[str, list[int], list[str], list[tuple[float, float]], np.ndarray]:
    """(robot name, q index, unit, (lower, upper)) of each named joint, and the neutral q.

    Raises:
        InputError: Unknown joints, a joint named twice, or a joint not of one coordinate.
    """
    spec = robot_spec(spec)  # a RobotSpec as given, a caller's text parsed
    if len(joints) != 2 or joints[0] == joints[1]:
        raise InputError("joints", "two different joint names", list(joints))
    chain = spec.chain
    if path == "denoc" and chain is not None:
        model, name = _linear_model(spec)
        names = list(model.joint_names)
        kinds = chain.joint_types if chain is not None else ("revolute",) * len(names)
        lengths = chain.lengths_m if chain is not None else (1.0,) * len(names)
        index = {n: i for i, n in enumerate(names)}
        units = {n: ("m" if k == "prismatic" else "rad") for n, k in zip(names, kinds, strict=True)}
        limits = {
            n: ((-l / 2, l / 2) if k == "prismatic" else (-math.pi, math.pi))
            for n, k, l in zip(names, kinds, lengths, strict=True)
        }
        neutral = np.zeros(len(names))
    else:  # the O(n) path reads a file's Model only, never a Data
        robot = _robot(spec) if path == "crba" else _file_robot(spec)
        model, name, names = robot.model, robot.name, list(robot.joint_names)
        index, units, limits = {}, {}, {}
        for j in range(1, model.njoints):
            joint = model.joints[j]
            if joint.nq != 1:
                continue
            jname, i = model.names[j], joint.idx_q
            index[jname] = i
            prismatic = joint_kind(joint) is JointKind.PRISMATIC
            units[jname] = "m" if prismatic else "rad"
            lo, hi = model.lowerPositionLimit[i], model.upperPositionLimit[i]
            if not (is_real_limit(lo) and is_real_limit(hi)):
                lo, hi = (-math.pi, math.pi) if not prismatic else (-1.0, 1.0)
            limits[jname] = (float(lo), float(hi))
        neutral = pin.neutral(model)
    for joint in joints:
        if joint not in names:
            hint = did_you_mean(joint, names).removeprefix("; ")
            raise InputError("joints", f"joints of {name}", joint, hint=hint)
        if joint not in index:
            raise InputError("joints", "joints of one coordinate (revolute or prismatic)", joint)
    return (
        name,
        [index[j] for j in joints],
        [units[j] for j in joints],
        [limits[j] for j in joints],
        neutral,
    )


class Execution(TypedDict, total=False):
    """How a map's chunks run: the keywords `conditioning_map` passes on to `run_chunks`.

    Attributes:
        workers: Local processes (1, the default: this process).
        scheduler: A Dask scheduler address or ``"local"`` (then ``workers`` is ignored).
        progress: Called with the fraction of chunks done.
    """

    workers: int | None
    scheduler: str | None
    progress: Callable[[float], None] | None


def run_chunks(
    tasks: Sequence[Task],
    starts: Sequence[int],
    shape: tuple[int, ...],
    metrics: Sequence[str],
    *,
    workers: int | None,
    scheduler: str | None,
    progress: Callable[[float], None] | None,
) -> tuple[dict[str, np.ndarray], bool]:
    """Run chunk tasks (each returns (len(metrics), k, ...)) into arrays of ``shape`` per metric.

    Chunk ``i`` fills rows ``starts[i]`` onwards; rows of unfinished chunks stay NaN.

    Returns:
        The arrays by metric, and whether Ctrl-C interrupted the sweep.
    """
    done = [0]

    def tick(_: int) -> None:
        done[0] += 1
        if progress is not None:
            progress(done[0] / len(tasks))

    outcome = run_sweep(tasks, workers=workers, scheduler=scheduler, progress=tick)
    values = {m: np.full(shape, np.nan) for m in metrics}
    for position, chunk in outcome.results.items():
        s = starts[position]
        for i, metric in enumerate(metrics):
            values[metric][s : s + chunk.shape[1]] = chunk[i]
    return values, outcome.interrupted


def _grid_chunk(spec, path, axes, base_q, x, y_rows, metrics) -> np.ndarray:
    """Metrics over rows ``y_rows`` × all of ``x``: an array (len(metrics), rows, nx).

    Rows are visited back and forth (serpentine), so that consecutive configurations are
    neighbours: the κ tracker of the O(n) path warm-starts from the previous point.
    """
    rows, nx = len(y_rows), len(x)
    xs = np.tile(x, rows).reshape(rows, nx)
    xs[1::2] = xs[1::2, ::-1]
    qs = np.repeat(np.asarray(base_q, dtype=float)[None, :], rows * nx, axis=0)
    qs[:, axes[0]] = xs.ravel()
    qs[:, axes[1]] = np.repeat(y_rows, nx)
    values = metrics_at(spec, path, qs, metrics).reshape(len(metrics), rows, nx)
    values[:, 1::2] = values[:, 1::2, ::-1]
    return values


def _numbers(value, name: str) -> np.ndarray:
    """``value`` as a float array, or one line naming ``name`` (not NumPy's ValueError)."""
    try:
        return np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(name, "numbers", value) from None


def _check_ranges(ranges) -> list[tuple[float, float]]:
    """Two (lower, upper) pairs as floats, or one line (a wrong shape, text, a scalar)."""
    limits = _numbers(ranges, "ranges")
    if limits.shape != (2, 2):
        raise InputError("ranges", "two (lower, upper) pairs, one per joint", ranges)
    return [(float(lo), float(hi)) for lo, hi in limits]


def conditioning_map(
    spec: RobotLike,
    joints: Sequence[str],
    *,
    grid: int = 50,
    ranges: Sequence[tuple[float, float]] | None = None,
    q: npt.ArrayLike | None = None,
    metrics: Sequence[str] = ("kappa", "diagonal_ratio"),
    backend: str = "auto",
    **execution: Unpack[Execution],
) -> ConditioningMap:
    """Metrics of M over a ``grid`` × ``grid`` map of two joints.

    Args:
        spec: The robot: a `Robot`, a `RobotSpec`, or ``chain:N``, a URDF path, an
            example-robot-data name (parsed and loaded once).
        joints: The two joints to sweep, by name (x then y).
        grid: Points per side, 2 to `MAX_GRID`.
        ranges: (lower, upper) per joint (default: its limits; ±π rad or ±1 m when none).
        q: The configuration of the other joints (default: neutral), length nq.
        metrics: Scalar metrics (`scalar_metrics`).
        backend: ``auto``, ``crba`` or ``denoc`` (as ``analyze``).
        **execution: How the chunks run (`Execution`): ``workers`` (local processes, 1: this
            process), ``scheduler`` (a Dask scheduler address or ``"local"``; then ``workers``
            is ignored), ``progress`` (called with the fraction of chunks done).
    """
    if (
        isinstance(grid, bool)
        or not isinstance(grid, (int, np.integer))
        or not 2 <= grid <= MAX_GRID
    ):
        raise InputError("grid", f"an integer from 2 to {MAX_GRID}", grid)
    spec = spec_of(spec)
    path = choose_path(spec, backend=backend)
    metrics = check_metrics(list(metrics), path)
    name, axes, units, limits, base_q = map_axes(spec, path, joints)
    if ranges is not None:
        limits = _check_ranges(ranges)
        for joint, (lo, hi) in zip(joints, limits, strict=True):
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise InputError("ranges", "finite lower < upper", (joint, lo, hi))
            if not math.isfinite(hi - lo):  # the grid's steps would overflow to inf
                raise InputError("ranges", "a span upper - lower below 1.8e308", (joint, lo, hi))
    if q is not None:
        base_q = checked_configurations(spec, path, _numbers(q, "q").ravel()[None, :])[0]
    x = np.linspace(*limits[0], grid)
    y = np.linspace(*limits[1], grid)
    rows = max(1, CHUNK_POINTS // grid)
    starts = range(0, grid, rows)
    per_point = 2e-4 if path == "denoc" else 2e-5
    tasks = [
        Task(
            _grid_chunk,
            (spec, path, axes, base_q, x, y[s : s + rows], metrics),
            rows * grid * per_point,
        )
        for s in starts
    ]
    values, interrupted = run_chunks(
        tasks,
        starts,
        (grid, grid),
        metrics,
        workers=execution.get("workers", 1),
        scheduler=execution.get("scheduler"),
        progress=execution.get("progress"),
    )
    return ConditioningMap(
        robot=name,
        joints=(joints[0], joints[1]),
        units=(units[0], units[1]),
        x=x,
        y=y,
        base_q=np.asarray(base_q, dtype=float),
        path=path,
        values=values,
        interrupted=interrupted,
    )
