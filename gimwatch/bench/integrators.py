"""Section ``integrators``: work-precision of gimwatch's integrators, MuJoCo as a peer.

The paper's swinging 10- and 20-link chains (``gimwatch/scenes/chain_10.toml``, ``chain_20.toml``:
straight and horizontal at rest, gravity −y in the plane of motion, 5 s) are run with every
integrator of [`Simulation`][gimwatch.simulation.simulate.Simulation]
and the ``aba`` backend, the δ watch on
(``diagonal_ratio`` at the scene's samples, every 0.01 s), energy evaluated at the samples:

* SciPy's DOP853, RK45, Radau, LSODA at rtol = atol = 1e-3 … 1e-12;
* fixed-step RK4 and semi-implicit Euler at dt = 1e-2 … 1e-5;
* MuJoCo's RK4 and (semi-implicit) Euler at the same steps, on the same URDF
  (`gimwatch.bench.mujoco_peer`; its mass matrix is checked against CRBA first).

Each run reports its final-state error max |q(T) − q_ref(T)| (rad) and velocity error
against a tight reference — DOP853 at rtol = atol = 1e-14 (SciPy raises rtol to 2.2e-14),
whose own uncertainty is estimated by its distance to DOP853 at 1e-13 — and the relative
energy drift, wall time (integration loop, samples included; median of 3 runs under
0.5 s), dynamics evaluations and steps. Runs are capped: a fixed-step run predicted
(from the previous step size) to exceed `CAP_S` is skipped, an adaptive run is
aborted at `CAP_S` and the tighter tolerances of that method are skipped; the rows
say so.
"""

from __future__ import annotations

import itertools
import time
import tomllib
import warnings
from dataclasses import dataclass

import numpy as np

from gimwatch.bench import BenchContext, SectionResult, Table, mujoco_peer
from gimwatch.bench.plots import plot_work_precision
from gimwatch.bench.report import markdown_table
from gimwatch.errors import InputError
from gimwatch.simulation.bundled_scenes import SCENES_DIR
from gimwatch.simulation.scene import parse_scene
from gimwatch.simulation.scene_integrator import MAX_FIXED_STEPS
from gimwatch.simulation.simulate import Simulation

__all__ = ["CAP_S", "COLUMNS", "TARGET_ERROR_RAD", "chain_scene_table", "run"]

SCENES = SCENES_DIR
ADAPTIVE = ("DOP853", "RK45", "Radau", "LSODA")
FIXED = ("RK4", "semi-implicit-euler")
TOLERANCES = tuple(10.0**-k for k in range(3, 13))
STEPS_S = (1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5)
CAP_S = 10.0
#: The acceptance's final-state error (rad) and the chain it is judged on.
TARGET_ERROR_RAD = 1e-10
TARGET_CHAIN = 10
COLUMNS = (
    "n",
    "simulator",
    "method",
    "rtol",
    "dt_s",
    "error_rad",
    "error_v",
    "energy_drift",
    "wall_s",
    "evaluations",
    "steps",
    "status",
)


def chain_scene_table(n: int, *, duration_s: float | None = None) -> dict:
    """The TOML table of ``gimwatch/scenes/chain_<n>.toml`` with the δ watch only and ``aba``.

    Args:
        n: 4, 10 or 20 (the scenes that exist).
        duration_s: Overrides the scene's duration when given.

    Raises:
        InputError: The scene file is missing (gimwatch run outside its checkout).
    """
    path = SCENES / f"chain_{n}.toml"
    try:
        table = tomllib.loads(path.read_text(encoding="utf-8"))
    except OSError as exc:
        raise InputError(str(path), "a readable scene file", "not found") from exc
    table["watch"] = {"metrics": ["diagonal_ratio"]}
    table.setdefault("dynamics", {})["backend"] = "aba"
    if duration_s is not None:
        table["duration"] = duration_s
    return table


def _simulate(table: dict, integrator: dict, cap_s: float):
    """One gimwatch run (median wall of 3 when under 0.5 s), or None when aborted at cap_s."""
    # the bench caps runs by wall time (cap_s), not by the scenes' default step budget
    integrator = {**integrator, "max_steps": MAX_FIXED_STEPS}
    scene = parse_scene({**table, "integrator": integrator}, source="<bench integrators>")
    walls: list[float] = []
    trajectory = None
    while len(walls) < (3 if not walls or walls[0] < 0.5 else 1):
        simulation = Simulation(scene)
        start = time.perf_counter()

        def stop_when_too_slow(_fraction: float, start=start) -> str | None:
            return "too slow" if time.perf_counter() - start > cap_s else None

        with warnings.catch_warnings():  # SciPy: "rtol too small, raised to 2.2e-14"
            warnings.simplefilter("ignore", UserWarning)
            trajectory = simulation.run(progress=stop_when_too_slow)
        if trajectory.status == "stopped":
            return None
        walls.append(trajectory.wall_time_s)
    return trajectory, float(np.median(walls))


@dataclass(frozen=True)
class _Reference:
    """One chain's scene table and its reference final state (DOP853 at 1e-14)."""

    n: int
    scene: dict
    q: np.ndarray
    v: np.ndarray


@dataclass(frozen=True)
class _Grid:
    """The tolerances and steps swept, and the wall-time cap of one run (s)."""

    tolerances: tuple[float, ...]
    steps: tuple[float, ...]
    cap_s: float


def _row(table: Table, ref: _Reference, simulator, method, rtol, dt, **values) -> None:
    q, v = values.pop("q", None), values.pop("v", None)
    ok = q is not None and values["status"] == "completed"
    table.add(
        n=ref.n,
        simulator=simulator,
        method=method,
        rtol=rtol,
        dt_s=dt,
        error_rad=float(np.abs(q - ref.q).max()) if ok else np.nan,
        error_v=float(np.abs(v - ref.v).max()) if ok else np.nan,
        **values,
    )


def _gimwatch_runs(context, table: Table, ref: _Reference, grid: _Grid) -> None:
    runs = [
        (m, {"method": m, "rtol": t, "atol": t}, t, np.nan)
        for m in ADAPTIVE
        for t in grid.tolerances
    ]
    runs += [(m, {"method": m, "dt": dt}, np.nan, dt) for m in FIXED for dt in grid.steps]
    capped: dict[str, str] = {}
    last_fixed: dict[str, tuple[float, float]] = {}
    for method, integrator, rtol, dt in runs:
        label = f"rtol {rtol:g}" if np.isfinite(rtol) else f"dt {dt:g}"
        if method in last_fixed:  # predicted wall time from the previous (larger) step
            prev_dt, prev_wall = last_fixed[method]
            if prev_wall * prev_dt / dt > grid.cap_s:
                capped[method] = f"skipped: predicted {prev_wall * prev_dt / dt:.0f} s > cap"
        result = None
        if method not in capped:
            context.progress(f"  chain:{ref.n}: gimwatch {method} {label}")
            result = _simulate(ref.scene, integrator, grid.cap_s)
            if result is None:
                capped[method] = f"aborted at the {grid.cap_s:g} s cap (or a looser tolerance was)"
        if result is None:  # skipped or aborted: a row saying why, without numbers
            _row(table, ref, "gimwatch", method, rtol, dt, energy_drift=np.nan, wall_s=np.nan,
                 evaluations=0, steps=0, status=capped[method])  # fmt: skip
            continue
        trajectory, wall = result
        if np.isfinite(dt):
            last_fixed[method] = (dt, wall)
        drift = trajectory.energy_drift()
        _row(table, ref, "gimwatch", method, rtol, dt,
             q=trajectory.q[-1], v=trajectory.v[-1],
             energy_drift=np.nan if drift is None else float(drift), wall_s=wall,
             evaluations=trajectory.rhs_evaluations, steps=trajectory.steps,
             status=trajectory.status)  # fmt: skip


def _mujoco_runs(context, table: Table, ref: _Reference, steps) -> None:
    simulation = Simulation(parse_scene(ref.scene, source="<bench integrators>"))
    assert simulation.gravity is not None  # the chain scenes swing under gravity
    model = mujoco_peer.load_model(simulation.robot.urdf_xml, simulation.gravity)
    for method in FIXED:
        for dt in steps:
            context.progress(f"  chain:{ref.n}: mujoco {method} dt {dt:g}")
            runs = [
                mujoco_peer.simulate(
                    model,
                    simulation.q0,
                    simulation.v0,
                    method=method,
                    dt=dt,
                    duration_s=simulation.scene.duration_s,
                    sample_s=simulation.scene.sample_s,
                )
                for _ in range(3)
            ]
            finite = np.all(np.isfinite(runs[0].q)) and np.all(np.isfinite(runs[0].v))
            _row(table, ref, "mujoco", method, np.nan, dt,
                 q=runs[0].q, v=runs[0].v, energy_drift=runs[0].energy_drift,
                 wall_s=float(np.median([r.wall_time_s for r in runs])),
                 evaluations=runs[0].steps * (4 if method == "RK4" else 1), steps=runs[0].steps,
                 status="completed" if finite else "diverged")  # fmt: skip


def _time_to_target(rows: list[dict], target: float) -> tuple[float, float]:
    """(measured, interpolated) wall time to reach ``target`` error on one curve (nan if not)."""
    points = sorted(
        (r["wall_s"], r["error_rad"]) for r in rows if np.isfinite(r["error_rad"] * r["wall_s"])
    )
    reached = [w for w, e in points if e <= target]
    measured = min(reached) if reached else np.nan
    interpolated = np.nan
    for (w0, e0), (w1, e1) in itertools.pairwise(points):
        if e0 > target >= e1:  # first crossing, log-log
            f = np.log(e0 / target) / np.log(e0 / e1)
            interpolated = float(np.exp(np.log(w0) + f * np.log(w1 / w0)))
            break
    if np.isnan(interpolated) and points and points[0][1] <= target:
        interpolated = points[0][0]
    return float(measured), float(interpolated)


def _acceptance(table: Table, n: int) -> dict:
    def curve(simulator, method):
        return [
            r for r in table.rows if (r["n"], r["simulator"], r["method"]) == (n, simulator, method)
        ]

    ours = _time_to_target(curve("gimwatch", "DOP853"), TARGET_ERROR_RAD)
    peer = _time_to_target(curve("mujoco", "RK4"), TARGET_ERROR_RAD)
    ratio = ours[1] / peer[1]
    return {
        "n": n,
        "gimwatch_dop853_measured_s": ours[0],
        "gimwatch_dop853_interpolated_s": ours[1],
        "mujoco_rk4_measured_s": peer[0],
        "mujoco_rk4_interpolated_s": peer[1],
        "ratio_interpolated": ratio,
        "ratio_measured": ours[0] / peer[0],
        "met": bool(ratio <= 0.5),
    }


def run(context: BenchContext) -> SectionResult:
    """Run every integrator on each chain, write ``integrators.csv`` and the plot."""
    chains = (4,) if context.quick else (10, 20)
    grid = (
        _Grid((1e-3, 1e-6), (1e-2, 5e-3), 5.0)
        if context.quick
        else _Grid(TOLERANCES, STEPS_S, CAP_S)
    )
    table = Table("integrators", COLUMNS)
    references = {}
    peer = mujoco_peer.available()
    for n in chains:
        scene = chain_scene_table(n, duration_s=0.2 if context.quick else None)
        context.progress(f"  chain:{n}: reference DOP853 at 1e-14 and 1e-13")
        reference, _ = _simulate(scene, {"method": "DOP853", "rtol": 1e-14, "atol": 1e-14}, 1e9)
        check, _ = _simulate(scene, {"method": "DOP853", "rtol": 1e-13, "atol": 1e-13}, 1e9)
        ref = _Reference(n, scene, reference.q[-1], reference.v[-1])
        references[n] = float(np.abs(check.q[-1] - ref.q).max())
        _gimwatch_runs(context, table, ref, grid)
        if peer:
            _mujoco_runs(context, table, ref, grid.steps)
    figure = plot_work_precision(table.rows, context.output / "work_precision.png")
    n_target = TARGET_CHAIN if TARGET_CHAIN in chains else chains[0]
    verdict, acceptance = _verdict(table, n_target, peer)
    text = _markdown(table, chains, references, verdict, peer)
    return SectionResult(
        name="integrators",
        title="Work-precision of integrators (MuJoCo peer)",
        tables=[table],
        figures=[figure],
        markdown=text,
        headline="\n".join([_headline_table(table, n_target), "", verdict]),
        summary={"reference_uncertainty_rad": references, "acceptance": acceptance},
    )


def _verdict(table: Table, n: int, peer: bool) -> tuple[str, dict | None]:
    if not peer:
        return "MuJoCo is not installed (`pip install gimwatch[peers]`): no peer rows.", None
    a = _acceptance(table, n)
    verdict = (
        f"Target: gimwatch's default simulation (DOP853, `aba`, δ watch on) reaching "
        f"{TARGET_ERROR_RAD:g} rad final-state error on the {n}-link chain in at most half "
        f"the wall time MuJoCo's RK4 needs. Time to {TARGET_ERROR_RAD:g} rad, interpolated "
        f"log-log on each curve: gimwatch {a['gimwatch_dop853_interpolated_s']:.3g} s, MuJoCo "
        f"RK4 {a['mujoco_rk4_interpolated_s']:.3g} s, ratio {a['ratio_interpolated']:.3g} "
        f"(first measured run at or below it: {a['gimwatch_dop853_measured_s']:.3g} s vs "
        f"{a['mujoco_rk4_measured_s']:.3g} s, ratio {a['ratio_measured']:.3g}) — "
        f"**{'met' if a['met'] else 'not met'}**."
    )
    return verdict, a


def _headline_table(table: Table, n: int) -> str:
    rows = []
    for simulator, method in dict.fromkeys((r["simulator"], r["method"]) for r in table.rows):
        curve = [
            r for r in table.rows if (r["n"], r["simulator"], r["method"]) == (n, simulator, method)
        ]
        _, interpolated = _time_to_target(curve, TARGET_ERROR_RAD)
        done = [r for r in curve if np.isfinite(r["error_rad"])]
        best = min(done, key=lambda r: r["error_rad"]) if done else None
        rows.append(
            {
                "what": f"{simulator} {method}",
                "t10": interpolated,
                "best": best["error_rad"] if best else None,
                "best_wall": best["wall_s"] if best else None,
                "drift": best["energy_drift"] if best else None,
            }
        )
    return markdown_table(
        rows,
        {
            "what": f"{n}-link chain",
            "t10": f"wall to {TARGET_ERROR_RAD:g} rad (s)",
            "best": "smallest error (rad)",
            "best_wall": "its wall (s)",
            "drift": "its energy drift",
        },
    )


def _markdown(table: Table, chains, references, verdict: str, peer: bool) -> str:
    capped = sorted({(r["method"], r["status"]) for r in table.rows if r["status"] != "completed"})
    lines = [
        "Final-state error max |q(T) − q_ref(T)| against DOP853 at rtol = atol = 1e-14 "
        "(SciPy raises rtol to 2.2e-14); the reference's distance to DOP853 at 1e-13: "
        + ", ".join(f"{v:.2g} rad (n = {n})" for n, v in references.items())
        + ". gimwatch runs use the `aba` backend with the δ watch and the energy at the "
        "scene's samples (every 0.01 s); wall time is the integration loop (median of 3 when "
        f"under 0.5 s); runs are capped at {CAP_S:g} s. "
        + ("MuJoCo steps with `mj_step(m, d, nstep)` between the same samples." if peer else ""),
        "",
        verdict,
        "",
    ]
    for n in chains:
        lines += [f"{n}-link chain:", "", _headline_table(table, n), ""]
    if capped:
        lines += ["Capped or failed runs (the rest of the table is in `integrators.csv`):", ""]
        lines += [f"- {method}: {status}" for method, status in capped] + [""]
    lines += [
        "All runs (`integrators.csv`):",
        "",
        markdown_table(
            table.rows,
            {
                "n": "n",
                "simulator": "sim",
                "method": "method",
                "rtol": "rtol",
                "dt_s": "dt (s)",
                "error_rad": "error (rad)",
                "energy_drift": "energy drift",
                "wall_s": "wall (s)",
                "evaluations": "FD evals",
                "status": "status",
            },
        ),
    ]
    return "\n".join(lines)
