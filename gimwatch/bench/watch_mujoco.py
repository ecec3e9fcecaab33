"""Section ``watch_mujoco``: what one watch sample costs inside a user's MuJoCo loop.

A robot compiled in MuJoCo with exact inertias (`gimwatch.model.mujoco_model.compile_robot`)
swings under gravity from seeded random joint angles (±1 rad) with ``mj_step`` (MuJoCo's default
Euler integrator, dt = `DT_S`); the watch is
[`from_mujoco`][gimwatch.watch.watch.Watch.from_mujoco] sampled after
every step. Watches (`WATCHES`): δ only (the diagonal entries of MuJoCo's sparse M, no M formed) and
κ (``mj_fullM`` + a symmetric eigen-solve), each either reading the M that ``mj_step`` left in
``data`` (``source = data``) or recomputing M at ``data.qpos`` on a private ``MjData``
(``source = qpos``: kinematics + composite rigid bodies).

Per (robot, watch, source), all in one run, each repeat timing the bare loop and every
watch back to back (ratios within a repeat, medians over repeats):

* ``step_us`` — one bare ``mj_step`` (a loop of steps timed whole);
* ``sample_us`` — one ``Watch.sample`` timed alone (a loop of samples on one ``data``);
* ``sample_vs_step`` = sample_us / step_us — the watch's cost per sample as a fraction of a
  step, the figure this section is for;
* ``loop_overhead`` — (loop with the watch) / (bare loop) - 1: the same cost seen end to
  end, a noisy difference of two run times.
"""

from __future__ import annotations

import time

import numpy as np
from threadpoolctl import threadpool_limits

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.report import markdown_table
from gimwatch.model.mujoco_model import compile_robot, compile_urdf
from gimwatch.model.robots import load_robot
from gimwatch.watch.watch import Watch

__all__ = ["COLUMNS", "ROBOTS", "WATCHES", "run"]

#: label -> (metrics, read the M in data (True) or recompute it at qpos (False)).
WATCHES: dict[str, tuple[tuple[str, ...], bool]] = {
    "delta/data": (("diagonal_ratio",), True),
    "kappa/data": (("kappa",), True),
    "delta/qpos": (("diagonal_ratio",), False),
    "kappa/qpos": (("kappa",), False),
}
#: Robots timed (quick runs take the first two).
ROBOTS = ("ur5", "chain:6", "panda", "chain:30")
DT_S = 1e-3
#: MuJoCo's ``boundinertia`` for the paper's rods (kg·m²), which have none about their axis.
INERTIA_FLOOR = 1e-9
COLUMNS = (
    "robot",
    "nv",
    "watch",
    "source",
    "steps",
    "step_us",
    "sample_us",
    "sample_vs_step",
    "loop_overhead",
)


def _robot_model(spec: str):
    robot = load_robot(spec)
    if robot.chain is None:
        model = compile_robot(robot)
    else:  # a rod has no inertia about its axis, which MuJoCo refuses: a floor, as for a peer
        model = compile_urdf(robot.urdf_xml, inertia_floor=INERTIA_FLOOR, spec=robot.spec)
    model.opt.timestep = DT_S
    return robot, model


def _loop_s(mujoco, model, qpos0, steps: int, sample=None) -> float:
    data = mujoco.MjData(model)
    data.qpos[:] = qpos0
    mujoco.mj_forward(model, data)
    start = time.perf_counter()
    if sample is None:
        for _ in range(steps):
            mujoco.mj_step(model, data)
    else:
        watch = sample(data)
        for _ in range(steps):
            mujoco.mj_step(model, data)
            watch(data)
    return time.perf_counter() - start


def _sampler(model, metrics: tuple[str, ...], read: bool):
    def make(data):
        watch = Watch.from_mujoco(model, data, metrics)
        if read:
            return lambda d: watch.sample(d.time)
        return lambda d: watch.sample(d.time, d.qpos)

    return make


def _sample_s(mujoco, model, qpos0, make, samples: int) -> float:
    """Mean time (s) of one sample, alone, on the data one step from ``qpos0``."""
    data = mujoco.MjData(model)
    data.qpos[:] = qpos0
    mujoco.mj_step(model, data)
    sample = make(data)
    start = time.perf_counter()
    for _ in range(samples):
        sample(data)
    return (time.perf_counter() - start) / samples


def measure(context: BenchContext) -> Table:
    """One row per (robot, watch); bare and watched runs interleaved in every repeat.

    Each repeat times the bare loop, then for every watch the watched loop and the samples
    alone; ratios are taken within a repeat (so a busy machine slows both sides) and the
    median over repeats is reported.
    """
    import mujoco

    robots = ROBOTS[:2] if context.quick else ROBOTS
    steps, repeats = (50, 2) if context.quick else (1000, 9)
    table = Table("watch_mujoco", COLUMNS)
    for spec in robots:
        robot, model = _robot_model(spec)
        rng = np.random.default_rng(context.seed)  # hinge joints only: angles in ±1 rad
        qpos0 = model.qpos0 + rng.uniform(-1.0, 1.0, model.nq)
        makers = {label: _sampler(model, *watch) for label, watch in WATCHES.items()}
        bare: list[float] = []
        loops: dict[str, list[float]] = {label: [] for label in WATCHES}
        samples: dict[str, list[float]] = {label: [] for label in WATCHES}
        context.progress(f"  {spec}: {repeats} x (bare mj_step, {len(WATCHES)} watches)")
        for _ in range(repeats):
            bare.append(_loop_s(mujoco, model, qpos0, steps))
            for label, make in makers.items():
                loops[label].append(_loop_s(mujoco, model, qpos0, steps, make))
                samples[label].append(_sample_s(mujoco, model, qpos0, make, steps))
        bare_s = np.asarray(bare)
        for label in WATCHES:
            step_s = bare_s / steps
            table.add(
                robot=robot.name,
                nv=robot.nv,
                watch=label.split("/")[0],
                source=label.split("/")[1],
                steps=steps,
                step_us=float(np.median(step_s)) * 1e6,
                sample_us=float(np.median(samples[label])) * 1e6,
                sample_vs_step=float(np.median(np.asarray(samples[label]) / step_s)),
                loop_overhead=float(np.median(np.asarray(loops[label]) / bare_s)) - 1.0,
            )
    return table


def run(context: BenchContext) -> SectionResult:
    """Measure and summarise the watch's cost per sample as a ratio to ``mj_step``."""
    with threadpool_limits(limits=1, user_api="blas"):
        table = measure(context)
    columns = {
        "robot": "robot",
        "nv": "nv",
        "watch": "watch",
        "source": "M from",
        "step_us": "mj_step (µs)",
        "sample_us": "one sample (µs)",
        "sample_vs_step": "sample / mj_step",
        "loop_overhead": "loop overhead",
    }
    data_rows = [r for r in table.rows if r["source"] == "data"]
    worst = {
        w: max(r["sample_vs_step"] for r in data_rows if r["watch"] == w)
        for w in ("delta", "kappa")
    }
    verdict = (
        f"Reading the M that `mj_step` left in `data`, one sample costs at most "
        f"{worst['delta']:.1%} of an `mj_step` watching δ and {worst['kappa']:.1%} watching κ "
        "on these robots (sampling every step; at one sample every 10 steps, a tenth of that)."
    )
    text = [
        f"MuJoCo `mj_step` (Euler, dt = {DT_S:g} s) under gravity from a seeded random "
        "configuration; `Watch.from_mujoco(model, data, metrics)` sampled after every step. "
        "`M from data`: the M `mj_step` computed (no dynamics recomputed); `M from qpos`: "
        "M recomputed at `data.qpos` on the watch's own `MjData`. `one sample` is timed alone; "
        "`loop overhead` is the whole loop with the watch against the bare loop (noisy).",
        "",
        markdown_table(table.rows, columns),
        "",
        verdict,
    ]
    return SectionResult(
        name="watch_mujoco",
        title="Cost of the watch in a MuJoCo loop",
        tables=[table],
        markdown="\n".join(text),
        headline="\n".join([markdown_table(data_rows, columns), "", verdict]),
        summary={
            "delta_sample_vs_step_max": worst["delta"],
            "kappa_sample_vs_step_max": worst["kappa"],
        },
    )
