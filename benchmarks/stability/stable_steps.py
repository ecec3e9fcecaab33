"""The stable-step table of docs/findings/stability.md: h* of the robots gimwatch ships or loads.

For each robot, held at its keyframe 0 (MJCF servo arms, their own servos) or its neutral
configuration (example-robot-data arms, PD gains stated below), gravity off as in MuJoCo's
divergence test: h* under MuJoCo's ``Euler``, ``implicitfast`` and ``RK4``, the critical
joint, what limits it, and κ, δ and κ_S of M at the same configuration. Then how far κ and δ
are from predicting h*: Spearman's rank correlation of h* with 1/κ, 1/δ and 1/λmax(K, M)
(the undamped stiffest mode, 2/ω) over the robots.

Run from the repository: ``python benchmarks/stability/stable_steps.py`` (about a minute);
writes ``benchmarks/stability/stable_steps.csv`` and ``summary.json`` beside this file.
"""

from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np
import scipy.linalg
import scipy.stats

from gimwatch.model.robots import load_robot
from gimwatch.stability.analysis import held_systems, stability

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
SERVO_ARMS = ROOT / "tests" / "data" / "mjcf" / "servo_arms"
INTEGRATORS = ("Euler", "implicitfast", "RK4")
#: PD gains of the example-robot-data arms (they ship none): N·m/rad and N·m·s/rad per joint.
KP, KD = 1000.0, 10.0
EXAMPLE_ARMS = ("ur5", "ur10", "panda", "talos_arm", "kinova", "z1")
COLUMNS = (
    "robot",
    "gains",
    "nv",
    "integrator",
    "h_star_s",
    "critical_joint",
    "limited_by",
    "two_over_omega_s",
    "kappa",
    "delta",
    "kappa_equilibrated",
)


def _conditioning(M: np.ndarray) -> tuple[float, float, float]:
    d = M.diagonal()
    S = M / np.sqrt(np.outer(d, d))
    return float(np.linalg.cond(M)), float(d.max() / d.min()), float(np.linalg.cond(S))


def _rows(robot, gains: str, **servos) -> list[dict]:
    qs, systems, _ = held_systems(robot, None, gravity=False, **servos)
    system = systems[0]
    kappa, delta, kappa_s = _conditioning(system.mass)
    omega_max = float(np.sqrt(scipy.linalg.eigvalsh(system.stiffness, system.mass).max()))
    rows = []
    for record in stability(robot, qs, integrators=INTEGRATORS, gravity=False, **servos):
        share = np.asarray(record.participation)
        joint = record.dof_names[int(share.argmax())] if share.size else ""
        rows.append(
            {
                "robot": robot.name,
                "gains": gains,
                "nv": robot.nv,
                "integrator": record.integrator,
                "h_star_s": f"{record.max_stable_timestep_s:.4g}",
                "critical_joint": joint,
                "limited_by": record.limited_by,
                "two_over_omega_s": f"{2.0 / omega_max:.4g}",
                "kappa": f"{kappa:.4g}",
                "delta": f"{delta:.4g}",
                "kappa_equilibrated": f"{kappa_s:.4g}",
            }
        )
    return rows


def measure_robot(name: str) -> list[dict]:
    """The rows of one robot: a servo arm (its file's stem) or an example-robot-data arm."""
    path = SERVO_ARMS / f"{name}.xml"
    if path.exists():
        return _rows(load_robot(str(path)), "own servos")
    return _rows(load_robot(name, floating=False), f"kp {KP:g} kd {KD:g}", kp=KP, kd=KD)


def measure() -> list[dict]:
    """Every row of the table: the servo arms with their own servos, then the gained arms."""
    names = [path.stem for path in sorted(SERVO_ARMS.glob("*.xml"))] + list(EXAMPLE_ARMS)
    return [row for name in names for row in measure_robot(name)]


def summary(rows: list[dict]) -> dict:
    """Spearman's ρ of h* with 1/κ, 1/δ and 2/ω over the robots, per integrator."""
    result = {}
    for integrator in INTEGRATORS:
        chosen = [r for r in rows if r["integrator"] == integrator]
        h = np.array([float(r["h_star_s"]) for r in chosen])
        result[integrator] = {
            f"spearman_h_star_vs_{name}": round(
                float(scipy.stats.spearmanr(h, np.array([f(r) for r in chosen])).statistic), 2
            )
            for name, f in (
                ("inverse_kappa", lambda r: 1 / float(r["kappa"])),
                ("inverse_delta", lambda r: 1 / float(r["delta"])),
                ("two_over_omega", lambda r: float(r["two_over_omega_s"])),
            )
        }
    return {"robots": len({r["robot"] for r in rows}), "kp": KP, "kd": KD, **result}


def page_table(rows: list[dict]) -> str:
    """The table of docs/findings/stability.md: one line per robot, h* per integrator."""
    lines = [
        "| robot | servos | h* Euler (s) | h* implicitfast (s) | h* RK4 (s) | 2/ω (s) "
        "| Euler limited by | κ | δ | κ_S |",
        "|---|---|---:|---:|---:|---:|---|---:|---:|---:|",
    ]
    for robot in dict.fromkeys(r["robot"] for r in rows):
        by = {r["integrator"]: r for r in rows if r["robot"] == robot}
        first = by["Euler"]
        lines.append(
            f"| {robot} | {first['gains']} | {by['Euler']['h_star_s']} "
            f"| {by['implicitfast']['h_star_s']} | {by['RK4']['h_star_s']} "
            f"| {first['two_over_omega_s']} | {first['limited_by']} ({first['critical_joint']}) "
            f"| {first['kappa']} | {first['delta']} | {first['kappa_equilibrated']} |"
        )
    return "\n".join(lines) + "\n"


def read_rows() -> list[dict]:
    """The committed rows."""
    with (HERE / "stable_steps.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


def main() -> None:
    """Measure, then write the CSV and the summary."""
    rows = measure()
    with (HERE / "stable_steps.csv").open("w", newline="") as handle:
        writer = csv.DictWriter(handle, COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    (HERE / "summary.json").write_text(json.dumps(summary(rows), indent=2) + "\n")


if __name__ == "__main__":
    main()
