"""Section ``digits``: the digits each solver of M q̈ = τ loses against mpmath; their predictor.

Each case is a URDF text, written in metres and rewritten in millimetres (lengths ×1000,
masses kept, inertias ×1e6: the same robot, coordinates in other units), at seeded random
configurations, at rest and without gravity (q̈ = M⁻¹ τ, τ random). Solvers:

* ``crba_cho_solve`` — Pinocchio's CRBA M, LAPACK Cholesky (``scipy.linalg.cho_factor/cho_solve``);
* ``crba_pin_ldlt`` — Pinocchio's CRBA and its sparse UDUᵀ (``pinocchio.cholesky``);
* ``aba`` — Pinocchio's articulated-body algorithm (no M);
* ``denoc`` — gimwatch's DeNOC O(n) forward dynamics (no M);
* ``mujoco_solveM`` — MuJoCo's ``mj_solveM`` on its own M (fixed bases; when MuJoCo imports).

Reference: an mpmath LU solve at 60 digits of the same float M (MuJoCo: its own M) and τ;
ABA and DeNOC are scored against the solve of CRBA's M. Errors: plain ‖x − x*‖/‖x*‖ and in the
D^1/2-weighted norm ‖D^1/2 (x − x*)‖/‖D^1/2 x*‖, D = diag M (the norm in which the
scaling-invariant bound of Cholesky holds: error ≲ c·κ_S·eps). Predictors of each row's M:
κ, κ_S = κ(D^-1/2 M D^-1/2), δ and the backward (UDUᵀ) pivot ratio.
"""

from __future__ import annotations

import xml.etree.ElementTree as ET
from typing import Any

import mpmath
import numpy as np
import pinocchio as pin
import scipy.linalg

from gimwatch.bench import BenchContext, SectionResult, Table
from gimwatch.bench.plots import EPS, plot_digits
from gimwatch.bench.report import markdown_table
from gimwatch.joint_kinds import length_positions
from gimwatch.metrics.conditioning import condition_number, diagonal_ratio, pivot_ratio_backward
from gimwatch.metrics.equilibrated import equilibrated_extremes
from gimwatch.model.chains import chain_spec, generate_chain_urdf

__all__ = [
    "COLUMNS",
    "SOLVERS",
    "case_table",
    "run",
    "scaled_urdf",
    "solver_table",
    "summary_by_solver",
]

SOLVERS = ("crba_cho_solve", "crba_pin_ldlt", "aba", "denoc", "mujoco_solveM")
COLUMNS = (
    "case",
    "unit",
    "floating",
    "nv",
    "sample",
    "solver",
    "kappa",
    "kappa_equilibrated",
    "diagonal_ratio",
    "pivot_ratio_backward",
    "rel_error",
    "energy_error",
    "rel_error_over_kappa_eps",
    "energy_error_over_kappa_s_eps",
)
#: Units of length the cases are written in, and their factor from metres.
UNITS = {"m": 1.0, "mm": 1000.0}
DIGITS = 60


def _chain(n: int, **options) -> str:
    return generate_chain_urdf(chain_spec(n, **options))


def _cases(quick: bool) -> list[tuple[str, str, bool]]:
    """(name, URDF text in metres, floating) of every case."""
    from gimwatch.model.robots import load_robot

    taper = np.geomspace(1.0, 0.01, 10)
    heavy = np.r_[100.0, np.full(9, 0.05)]
    heavier = np.r_[1e4, np.full(9, 1e-3)]  # 1e7 between base and leaves
    near = np.r_[1.0, 1e-4, np.ones(8)]  # joints 2 and 3 nearly on one axis
    nearer = np.r_[1.0, 1e-6, np.ones(8)]
    slides = ["revolute", "prismatic"] * 4
    cases = [
        ("chain_10", _chain(10), False),
        ("chain_20", _chain(20), False),
        ("chain_40", _chain(40), False),
        ("tapered_10", _chain(10, mass_kg=2.2 * taper, length_m=np.geomspace(1, 0.1, 10)), False),
        ("heavy_base_10", _chain(10, mass_kg=heavy), False),
        ("heavy_base_1e7_10", _chain(10, mass_kg=heavier), False),
        ("near_axes_10", _chain(10, length_m=near, mass_kg=2.2 * near), False),
        ("near_axes_1e-6_10", _chain(10, length_m=nearer, mass_kg=2.2 * nearer), False),
        ("spatial_slide_8", _chain(8, axes="spatial", joint_types=slides), False),
    ]
    robots = [("ur5", False), ("panda", False), ("ur5", True), ("solo12", True)]
    if not quick:
        robots += [("talos_arm", False), ("talos_arm", True)]
    for name, floating in robots:
        robot = load_robot(name, floating=False)
        cases.append((f"{name}{'_floating' if floating else ''}", robot.urdf_xml, floating))
    return cases[:3] + cases[-2:] if quick else cases


def scaled_urdf(urdf_xml: str, factor: float) -> str:
    """The same robot with lengths ×factor, masses kept, inertias ×factor² (visuals dropped)."""
    root = ET.fromstring(urdf_xml)
    for link in root.iter("link"):
        for tag in ("visual", "collision"):
            for element in link.findall(tag):
                link.remove(element)
    for origin in root.iter("origin"):
        xyz = [float(x) * factor for x in origin.get("xyz", "0 0 0").split()]
        origin.set("xyz", " ".join(repr(x) for x in xyz))
    for inertia in root.iter("inertia"):
        for key in ("ixx", "ixy", "ixz", "iyy", "iyz", "izz"):
            inertia.set(key, repr(float(inertia.get(key, "0")) * factor**2))
    for joint in root.iter("joint"):
        limit = joint.find("limit")
        if joint.get("type") == "prismatic" and limit is not None:
            for key in ("lower", "upper"):
                value = limit.get(key)
                if value is not None:
                    limit.set(key, repr(float(value) * factor))
    return ET.tostring(root, encoding="unicode")


def _model(xml: str, floating: bool) -> pin.Model:
    model = (
        pin.buildModelFromXML(xml, pin.JointModelFreeFlyer())
        if floating
        else pin.buildModelFromXML(xml)
    )
    model.gravity = pin.Motion.Zero()
    return model


def _length_coordinates(model: pin.Model) -> np.ndarray:
    """Mask of the q coordinates that are lengths (prismatic, free-flyer translation)."""
    mask = np.zeros(model.nq, dtype=bool)
    for joint in model.joints[1:]:
        mask[joint.idx_q : joint.idx_q + length_positions(joint)] = True
    return mask


def _configurations(model: pin.Model, count: int, seed: int) -> np.ndarray:
    """Seeded uniform draws within the limits (±π rad, ±1 m where a limit is missing)."""
    lower = np.where(np.isfinite(model.lowerPositionLimit), model.lowerPositionLimit, -1.0)
    upper = np.where(np.isfinite(model.upperPositionLimit), model.upperPositionLimit, 1.0)
    lower, upper = np.maximum(lower, -np.pi), np.minimum(upper, np.pi)
    rng = np.random.default_rng(seed)
    return np.array([pin.normalize(model, rng.uniform(lower, upper)) for _ in range(count)])


def _reference(M: np.ndarray, tau: np.ndarray) -> np.ndarray:
    with mpmath.workdps(DIGITS):
        x = mpmath.lu_solve(mpmath.matrix(M.tolist()), mpmath.matrix(tau.tolist()))
        return np.array([float(v) for v in x])


def _errors(x: np.ndarray, exact: np.ndarray, M: np.ndarray) -> tuple[float, float]:
    w = np.sqrt(np.diag(M))
    plain = np.linalg.norm(x - exact) / np.linalg.norm(exact)
    return float(plain), float(np.linalg.norm(w * (x - exact)) / np.linalg.norm(w * exact))


def _predictors(M: np.ndarray) -> dict:
    low, high = equilibrated_extremes(M)
    return {
        "kappa": condition_number(M),
        "kappa_equilibrated": high / low,
        "diagonal_ratio": diagonal_ratio(M),
        "pivot_ratio_backward": pivot_ratio_backward(M),
    }


def _mujoco(xml: str):
    """MuJoCo's model of the URDF, or None (not installed, or it refuses the file)."""
    from gimwatch.bench import mujoco_peer

    if not mujoco_peer.available():
        return None
    try:
        return mujoco_peer.load_model(xml, np.zeros(3))
    except Exception:  # a peer that cannot read a file is left out
        return None


def _mujoco_rows(mj, q: np.ndarray, rng) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    import mujoco

    if mj.nq != q.size:
        return None
    data = mujoco.MjData(mj)
    data.qpos[:] = q
    mujoco.mj_forward(mj, data)
    M = np.zeros((mj.nv, mj.nv))
    mujoco.mj_fullM(mj, data, M)
    tau = M @ rng.standard_normal(mj.nv)  # as for the other solvers: a q̈ of every coordinate
    x = np.zeros((1, mj.nv))
    mujoco.mj_solveM(mj, data, x, tau[None, :].copy())
    return M, tau, x[0]


def _case_rows(table, name, xml, floating, unit, configurations, seed) -> None:
    from gimwatch.denoc import DenocModel

    model = _model(xml, floating)
    data = model.createData()
    joint_order = list(model.names[1:])
    try:
        denoc = DenocModel.from_urdf(xml, floating=floating, joint_order=joint_order)
    except Exception:  # a joint type DeNOC does not read: no row
        denoc = None
    mj = None if floating else _mujoco(xml)
    rng = np.random.default_rng(seed)
    scale = np.where(_length_coordinates(model), UNITS[unit], 1.0)
    for k, q_m in enumerate(configurations):
        q = q_m * scale  # the same configuration as in metres, lengths in the case's unit
        M = pin.crba(model, data, q)
        M = np.triu(M) + np.triu(M, 1).T
        tau = M @ rng.standard_normal(model.nv)  # a q̈ of every coordinate, in its unit
        exact = _reference(M, tau)
        found = {"crba_cho_solve": scipy.linalg.cho_solve(scipy.linalg.cho_factor(M), tau)}
        pin.crba(model, data, q)
        pin.cholesky.decompose(model, data)
        found["crba_pin_ldlt"] = np.array(pin.cholesky.solve(model, data, tau))
        found["aba"] = np.array(pin.aba(model, data, q, np.zeros(model.nv), tau))
        if denoc is not None and np.allclose(denoc.gim(q), M, rtol=1e-9, atol=1e-12 * M.max()):
            zero = np.zeros(3)
            found["denoc"] = np.asarray(
                denoc.forward_dynamics(q, np.zeros(model.nv), tau, gravity=zero)
            )
        predictors = _predictors(M)
        common = {"case": name, "unit": unit, "floating": floating, "nv": model.nv, "sample": k}
        for solver, x in found.items():
            _add(table, common, solver, predictors, *_errors(x, exact, M))
        peer = None if mj is None else _mujoco_rows(mj, q, rng)
        if peer is not None:
            M_mj, tau_mj, x = peer
            _add(
                table,
                common,
                "mujoco_solveM",
                _predictors(M_mj),
                *_errors(x, _reference(M_mj, tau_mj), M_mj),
            )


def _add(table, common, solver, predictors, plain, energy) -> None:
    table.add(
        **common,
        solver=solver,
        **predictors,
        rel_error=plain,
        energy_error=energy,
        rel_error_over_kappa_eps=plain / (predictors["kappa"] * EPS),
        energy_error_over_kappa_s_eps=energy / (predictors["kappa_equilibrated"] * EPS),
    )


def run(context: BenchContext) -> SectionResult:
    """Score each solver against mpmath on every case, in metres and millimetres."""
    samples = 1 if context.quick else 3
    table = Table("digits", COLUMNS)
    for name, xml_m, floating in _cases(context.quick):
        configurations = _configurations(_model(xml_m, floating), samples, context.seed)
        for unit, factor in UNITS.items():
            context.progress(f"  {name} ({unit})")
            xml = xml_m if factor == 1.0 else scaled_urdf(xml_m, factor)
            _case_rows(table, name, xml, floating, unit, configurations, context.seed)
    figure = plot_digits(table.rows, context.output / "digits.png")
    return _result(table, figure)


def summary_by_solver(rows: list[dict]) -> dict[str, dict[str, float]]:
    """Per solver: worst error/(κ·eps), worst energy error/(κ_S·eps), worst digits lost."""
    out = {}
    for solver in dict.fromkeys(r["solver"] for r in rows):
        mine = [r for r in rows if r["solver"] == solver]
        out[solver] = {
            "rows": len(mine),
            "max_rel_error_over_kappa_eps": max(r["rel_error_over_kappa_eps"] for r in mine),
            "max_energy_error_over_kappa_s_eps": max(
                r["energy_error_over_kappa_s_eps"] for r in mine
            ),
            "max_digits_lost": float(np.log10(max(max(r["rel_error"] for r in mine), EPS) / EPS)),
        }
    return out


def _numeric(rows: list[dict]) -> list[dict]:
    """Rows as read back from the CSV (strings) or as measured: floats where numbers."""
    out = []
    for row in rows:
        parsed = {}
        for key, value in row.items():
            try:
                parsed[key] = value if key in ("case", "unit", "solver") else float(value)
            except (TypeError, ValueError):
                parsed[key] = value
        out.append(parsed)
    return out


def solver_table(rows: list[dict]) -> str:
    """Per solver, worst over every case and unit: the Markdown table the findings quote."""
    wide: list[dict[str, Any]] = [
        {"solver": s, **v} for s, v in summary_by_solver(_numeric(rows)).items()
    ]
    for row in wide:
        row["rows"] = int(row["rows"])
    columns = {
        "solver": "solver",
        "rows": "rows",
        "max_rel_error_over_kappa_eps": "max error/(κ·eps)",
        "max_energy_error_over_kappa_s_eps": "max energy error/(κ_S·eps)",
        "max_digits_lost": "max digits lost",
    }
    return markdown_table(wide, columns)


def case_table(rows: list[dict]) -> str:
    """Per case and unit, at its worst sample: the predictors and the worst solver's errors."""
    rows = _numeric(rows)
    wide = []
    for case in dict.fromkeys(r["case"] for r in rows):
        for unit in UNITS:
            mine = [r for r in rows if r["case"] == case and r["unit"] == unit]
            if not mine:
                continue
            worst = max(mine, key=lambda r: r["rel_error"])
            same_m = [r for r in mine if r["sample"] == worst["sample"]]
            base = next(r for r in same_m if r["solver"] == "crba_cho_solve")
            wide.append(
                {
                    "case": case,
                    "unit": unit,
                    "nv": int(base["nv"]),
                    **{k: base[k] for k in ("kappa", "kappa_equilibrated", "diagonal_ratio")},
                    "pivot_ratio_backward": base["pivot_ratio_backward"],
                    "rel_error": worst["rel_error"],
                    "solver": worst["solver"],
                    "energy": max(r["energy_error_over_kappa_s_eps"] for r in same_m),
                }
            )
    columns = {
        "case": "case",
        "unit": "unit",
        "nv": "nv",
        "kappa": "κ",
        "kappa_equilibrated": "κ_S",
        "diagonal_ratio": "δ",
        "pivot_ratio_backward": "pivot ratio (UDUᵀ)",
        "rel_error": "worst error",
        "solver": "by",
        "energy": "worst energy error/(κ_S·eps)",
    }
    return markdown_table(wide, columns)


def _result(table: Table, figure) -> SectionResult:
    summary = summary_by_solver(table.rows)
    text = [
        "Error of q̈ = M⁻¹τ against an mpmath solve (60 digits) of the same float M and τ, "
        "in metres and millimetres; energy error in the D^1/2-weighted norm.",
        "",
        solver_table(table.rows),
        "",
        "Per case (M's predictors at the sample where a solver erred most):",
        "",
        case_table(table.rows),
    ]
    return SectionResult(
        name="digits",
        title="Digits lost per solver, and their predictor",
        tables=[table],
        figures=[figure],
        markdown="\n".join(text),
        headline="\n".join(text[:3]),
        summary=summary,
    )
