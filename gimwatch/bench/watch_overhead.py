"""Section ``watch_overhead``: a watch sample against the two lines a user would write.

Per robot (a 7-DoF arm, a quadruped on a free joint, a humanoid on a free joint), in one
process, interleaved rounds, medians: each watch sample is timed against the bare user
computation of the same quantity and against one step of the loop it sits in.

* MuJoCo loop (``Watch.from_mujoco(model, data, ...)``, ``sample(t)`` reading ``data``):
  κ against ``mj_fullM`` + ``numpy.linalg.eigvalsh``; δ against ``data.M[dof_Madr]``
  max/min; both against ``mj_step``.
* Pinocchio loop (``Watch.from_model(model, ...)`` as docs/watch.md shows it, loop
  ``pinocchio``; ``Watch(robot, ...)``, loop ``robot``; ``sample(t, q)``): κ against
  ``pin.crba`` + ``eigvalsh``; δ against the O(n) diagonal (DeNOC's compiled diag M,
  max/min, unchecked q); both against ``pin.aba``.

A second table (``watch_tracker``): on the paper's rod chains of n links moved smoothly
(``Watch(robot, ...)``, one sample per small step in q), a κ sample by the dense solve
(``kappa``: CRBA + the compiled eigen-solve) against the O(n) tracker (``kappa_tracked``),
to say from which n the tracker pays.

A third table (``watch_solver``): the watch's dense eigen-solve
([`SpectrumSolver`][gimwatch.watch.spectrum_solver.SpectrumSolver]) against NumPy's
``eigvalsh`` on one symmetric positive definite matrix per size, across the sizes where the
solver changes (the numba kernel, ``dsyevd`` with its minimal then its optimal workspace).

Columns: ``bare_us``, ``watch_us``, ``step_us`` (medians, µs), ``watch_vs_bare`` and
``watch_vs_step`` (medians of the per-round ratios).
"""

from __future__ import annotations

import time

import numpy as np
import pinocchio as pin
from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.report import markdown_table
from gimwatch.metrics.tracker.providers import lean_model
from gimwatch.model.mujoco_model import compile_robot
from gimwatch.model.robots import load_robot
from gimwatch.watch.spectrum_solver import COMPILED_MAX_NV, UNBLOCKED_MAX_NV, SpectrumSolver
from gimwatch.watch.watch import Watch

__all__ = [
    "CHAIN_SIZES",
    "COLUMNS",
    "ROBOTS",
    "SOLVER_COLUMNS",
    "SOLVER_SIZES",
    "TRACKER_COLUMNS",
    "run",
]

#: (spec, floating base): a 7-DoF arm, a quadruped and a humanoid on free joints.
ROBOTS = (("xarm7", False), ("solo12", True), ("g1", True))
#: Chain sizes (links) of the tracker table.
CHAIN_SIZES = (10, 20, 30, 50, 100)
TRACKER_COLUMNS = ("n", "samples", "dense_us", "tracked_us", "tracked_vs_dense")
#: Matrix sizes of the solver table: each side of each switch of `SpectrumSolver`.
SOLVER_SIZES = (
    7,
    20,
    COMPILED_MAX_NV,
    COMPILED_MAX_NV + 1,
    50,
    UNBLOCKED_MAX_NV,
    UNBLOCKED_MAX_NV + 1,
    200,
)
SOLVER_COLUMNS = ("n", "solver", "numpy_us", "solver_us", "solver_vs_numpy")
COLUMNS = (
    "robot",
    "nv",
    "loop",
    "metric",
    "bare_us",
    "watch_us",
    "step_us",
    "watch_vs_bare",
    "watch_vs_step",
)


def _per_call_s(call, calls: int) -> float:
    start = time.perf_counter()
    for _ in range(calls):
        call()
    return (time.perf_counter() - start) / calls


def _mujoco_cases(robot, seed: int):
    import mujoco

    model = compile_robot(robot)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(seed)
    hinges = model.jnt_type == mujoco.mjtJoint.mjJNT_HINGE
    qpos = model.qpos0.copy()
    for j in np.flatnonzero(hinges):
        qpos[model.jnt_qposadr[j]] += rng.uniform(-1.0, 1.0)
    data.qpos[:] = qpos
    mujoco.mj_forward(model, data)
    M = np.empty((model.nv, model.nv))
    adr = model.dof_Madr

    def bare_kappa():
        mujoco.mj_fullM(model, data, M)
        values = np.linalg.eigvalsh(M)
        return values[-1] / values[0]

    def bare_delta():
        diag = data.M[adr]
        return diag.max() / diag.min()

    kappa = Watch.from_mujoco(model, data, ("kappa",))
    delta = Watch.from_mujoco(model, data, ("diagonal_ratio",))
    step_data = mujoco.MjData(model)
    step_data.qpos[:] = qpos

    def step():
        mujoco.mj_step(model, step_data)

    return step, {
        "kappa": (bare_kappa, lambda: kappa.sample(0.0)),
        "delta": (bare_delta, lambda: delta.sample(0.0)),
    }


def _pinocchio_cases(robot, seed: int, *, from_model: bool = True):
    """The Pinocchio loop: its step, and per metric (bare lines, watch sample).

    The watch as docs/watch.md builds it there (``from_model``) or from the gimwatch robot.
    """
    model, data = robot.model, robot.new_data()
    q = pin.randomConfiguration(model, -np.ones(model.nq), np.ones(model.nq))
    v = np.zeros(model.nv)
    lean = lean_model(robot)

    def bare_kappa():
        values = np.linalg.eigvalsh(pin.crba(model, data, q))
        return values[-1] / values[0]

    def bare_delta():
        diag = lean.gim_diagonal(q)
        return diag.max() / diag.min()

    if from_model:
        kappa = Watch.from_model(model, ("kappa",))
        delta = Watch.from_model(model, ("diagonal_ratio",))
    else:
        kappa, delta = Watch(robot, ("kappa",)), Watch(robot, ("diagonal_ratio",))
    return lambda: pin.aba(model, data, q, v, v), {
        "kappa": (bare_kappa, lambda: kappa.sample(0.0, q)),
        "delta": (bare_delta, lambda: delta.sample(0.0, q)),
    }


def measure(context: BenchContext) -> Table:
    """One row per (robot, loop, metric); every round times step, bare and watch in turn."""
    calls, rounds = (200, 3) if context.quick else (2000, 15)
    robots = ROBOTS[:1] if context.quick else ROBOTS
    table = Table("watch_overhead", COLUMNS)
    for spec, floating in robots:
        robot = load_robot(spec, floating=floating)
        loops = (
            ("mujoco", _mujoco_cases),
            ("pinocchio", _pinocchio_cases),
            ("robot", lambda robot, seed: _pinocchio_cases(robot, seed, from_model=False)),
        )
        for loop, build in loops:
            step, cases = build(robot, context.seed)
            context.progress(f"  {spec} ({loop}): {rounds} rounds")
            times: dict[str, list[float]] = {
                key: [] for key in ("step", *[f"{m}/{s}" for m in cases for s in "bw"])
            }
            for call in (step, *[c for pair in cases.values() for c in pair]):
                call()  # warm-up: compiled kernels, buffers
            for _ in range(rounds):
                times["step"].append(_per_call_s(step, calls))
                for metric, (bare, watch) in cases.items():
                    times[f"{metric}/b"].append(_per_call_s(bare, calls))
                    times[f"{metric}/w"].append(_per_call_s(watch, calls))
            step_s = np.asarray(times["step"])
            for metric in cases:
                bare_s, watch_s = np.asarray(times[f"{metric}/b"]), np.asarray(times[f"{metric}/w"])
                table.add(
                    robot=spec,
                    nv=robot.nv,
                    loop=loop,
                    metric=metric,
                    bare_us=float(np.median(bare_s)) * 1e6,
                    watch_us=float(np.median(watch_s)) * 1e6,
                    step_us=float(np.median(step_s)) * 1e6,
                    watch_vs_bare=float(np.median(watch_s / bare_s)),
                    watch_vs_step=float(np.median(watch_s / step_s)),
                )
    return table


def measure_tracker(context: BenchContext) -> Table:
    """One row per chain size: κ per sample, dense solve against the tracker, same path."""
    samples, rounds = (20, 2) if context.quick else (200, 5)
    sizes = CHAIN_SIZES[:2] if context.quick else CHAIN_SIZES
    table = Table("watch_tracker", TRACKER_COLUMNS)
    for n in sizes:
        robot = load_robot(f"chain:{n}")
        rng = np.random.default_rng(context.seed)
        start, direction = rng.uniform(-1.0, 1.0, n), rng.uniform(-1.0, 1.0, n)
        path = [start + 1e-3 * k * direction for k in range(samples)]
        context.progress(f"  chain:{n}: dense κ against the tracker, {rounds} rounds")
        times: dict[str, list[float]] = {"kappa": [], "kappa_tracked": []}
        for _ in range(rounds):
            for metric in times:
                watch = Watch(robot, (metric,))
                watch.sample(0.0, path[0])  # warm: compiled kernels, the tracker's start
                begin = time.perf_counter()
                for k, q in enumerate(path):
                    watch.sample(float(k), q)
                times[metric].append((time.perf_counter() - begin) / samples)
        dense, tracked = np.asarray(times["kappa"]), np.asarray(times["kappa_tracked"])
        table.add(
            n=n,
            samples=samples,
            dense_us=float(np.median(dense)) * 1e6,
            tracked_us=float(np.median(tracked)) * 1e6,
            tracked_vs_dense=float(np.median(tracked / dense)),
        )
    return table


def _solver_name(n: int) -> str:
    if n <= COMPILED_MAX_NV:
        return "numba kernel"
    return "dsyevd, minimal workspace" if n <= UNBLOCKED_MAX_NV else "dsyevd, optimal workspace"


def measure_solver(context: BenchContext) -> Table:
    """One row per size: the watch's eigen-solve against ``numpy.linalg.eigvalsh``."""
    rounds = 2 if context.quick else 7
    sizes = SOLVER_SIZES[2:4] if context.quick else SOLVER_SIZES
    table = Table("watch_solver", SOLVER_COLUMNS)
    rng = np.random.default_rng(context.seed)
    for n in sizes:
        A = rng.standard_normal((n, n))
        M = A @ A.T + n * np.eye(n)
        solver = SpectrumSolver(n)
        calls = max(10, min(2000, 200_000 // n**2))
        numpy_call = lambda M=M: np.linalg.eigvalsh(M)  # noqa: E731 - timed as written
        solver_call = lambda M=M, solver=solver: solver.ratio(M)  # noqa: E731
        numpy_call(), solver_call()
        rounds_s = np.array(
            [
                (_per_call_s(numpy_call, calls), _per_call_s(solver_call, calls))
                for _ in range(rounds)
            ]
        )
        numpy_s, solver_s = rounds_s[:, 0], rounds_s[:, 1]
        table.add(
            n=n,
            solver=_solver_name(n),
            numpy_us=float(np.median(numpy_s)) * 1e6,
            solver_us=float(np.median(solver_s)) * 1e6,
            solver_vs_numpy=float(np.median(solver_s / numpy_s)),
        )
    return table


#: Report headings of the three tables' columns.
_HEADS = {
    "robot": "robot",
    "nv": "nv",
    "loop": "loop",
    "metric": "metric",
    "bare_us": "bare (µs)",
    "watch_us": "watch (µs)",
    "step_us": "step (µs)",
    "watch_vs_bare": "watch / bare",
    "watch_vs_step": "watch / step",
}
_TRACKER_HEADS = {
    "n": "n",
    "dense_us": "dense κ (µs)",
    "tracked_us": "tracked κ (µs)",
    "tracked_vs_dense": "tracked / dense",
}
_SOLVER_HEADS = {
    "n": "n",
    "solver": "watch's solver",
    "numpy_us": "NumPy eigvalsh (µs)",
    "solver_us": "watch's solve (µs)",
    "solver_vs_numpy": "watch / NumPy",
}


def run(context: BenchContext) -> SectionResult:
    """Measure the watch's sample against the bare computation and the loop's step."""
    with threadpool_limits(limits=1, user_api="blas"):
        table = measure(context)
        tracker = measure_tracker(context)
        solver = measure_solver(context)
    text = [
        "One watch sample against the user's own computation of the same quantity "
        "(MuJoCo: `mj_fullM` + `eigvalsh`, `data.M[dof_Madr]` max/min; Pinocchio: `pin.crba` "
        "+ `eigvalsh`, DeNOC's O(n) diagonal) and against one step of the loop (`mj_step`, "
        "`pin.aba`); medians of interleaved rounds, ratios within a round. Loop `mujoco`: "
        "`Watch.from_mujoco(model, data, ...)`; `pinocchio`: `Watch.from_model(model, ...)`; "
        "`robot`: `Watch(robot, ...)`.",
        "",
        markdown_table(table.rows, _HEADS),
        "",
        "κ per sample along a smooth path on rod chains: the dense solve (`kappa`) against "
        "the O(n) tracker (`kappa_tracked`), both through `Watch(robot, ...)`.",
        "",
        markdown_table(tracker.rows, _TRACKER_HEADS),
        "",
        "The watch's dense eigen-solve (`SpectrumSolver`, κ of one matrix) against NumPy's "
        "`eigvalsh` on a symmetric positive definite matrix of each size, ratios within a round.",
        "",
        markdown_table(solver.rows, _SOLVER_HEADS),
    ]
    worst = {
        m: max(r["watch_vs_bare"] for r in table.rows if r["metric"] == m)
        for m in ("kappa", "delta")
    }
    return SectionResult(
        name="watch_overhead",
        title="The watch sample against the bare computation",
        tables=[table, tracker, solver],
        markdown="\n".join(text),
        headline="\n".join(text),
        summary={f"{m}_watch_vs_bare_max": v for m, v in worst.items()},
    )
