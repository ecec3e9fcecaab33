"""Exact sensitivities of κ(M(q)) to every inertial parameter, link offset and armature.

First-order eigenvalue perturbation: for a simple eigenvalue λ with unit eigenvector v,
``∂λ/∂p = vᵀ (∂M/∂p) v``, and ``∂κ/∂p = (∂λmax/∂p − κ ∂λmin/∂p) / λmin`` for κ = λmax/λmin.
∂M/∂p comes without finite differences from ``M = Σ_b J_bᵀ I_b J_b + diag(a)``:

* mass, centre of mass (body frame, m) and inertia about the centre of mass (body axes,
  kg·m²): ``∂M/∂p = J_bᵀ (∂I_b/∂p) J_b`` with ∂I_b/∂p the derivative of the spatial inertia
  ``[[m1, −m[c]×], [m[c]×, I_c − m[c]×²]]`` (Pinocchio's layout), in closed form;
* a link offset (the translation of joint j's placement, in its parent's frame, m): the
  subtree of j moves rigidly by ``d = R_parent e`` at fixed q, so bodies and joint axes of the
  subtree translate while the other joints' axes stay. With ``D = [[0, −[d]×], [0, 0]]``
  (a twist about the moved origin), ``∂M/∂t = Σ_{b ∈ sub(j)} (D J_bᴬ)ᵀ I_b J_b + J_bᵀ I_b (D J_bᴬ)``
  in the world frame, where J_bᴬ keeps only the columns of joints outside the subtree;
* armature a_i (kg·m² for a revolute coordinate, kg for a prismatic one): ``∂M/∂a_i = e_i e_iᵀ``.

Clustered eigenvalues: λmin (λmax) is taken as a cluster when other eigenvalues lie within
``cluster_rtol`` of it (relative, floored at 100·eps·λmax, float64's resolution). The
eigenvalue of a cluster is not differentiable; what is reported is its exact one-sided
derivative as p increases, ``∂⁺λmin = λmin(Vᵀ ∂M V)`` and ``∂⁺λmax = λmax(Vᵀ ∂M V)`` over the
cluster's eigenvectors V (Kato's perturbation theory), and the result is flagged ``clustered``.

Elasticities ``∂ log κ / ∂ log p = (p/κ) ∂κ/∂p`` are reported where p ≠ 0 (0 where p = 0:
the logarithm is undefined and the parameter has no scale; see ``dkappa`` for those).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.explain.bodies import BodySplit, body_names, body_split, dof_joint_ranges
from gimwatch.joint_kinds import length_velocities
from gimwatch.metrics.conditioning import extreme_ratio
from gimwatch.metrics.dense_analysis import check_robot_gim
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = [
    "CLUSTER_RTOL",
    "METRICS",
    "KappaSensitivities",
    "Sensitivity",
    "kappa_sensitivities",
    "parameter_table",
    "spatial_inertia_derivatives",
]

#: The metrics whose sensitivities are computed exactly.
METRICS = ("kappa", "kappa_equilibrated")
#: Eigenvalues closer than this (relative) to λmin or λmax are treated as one cluster.
CLUSTER_RTOL = 1e-8
_INERTIA_ENTRIES: tuple[tuple[str, int, int], ...] = (
    ("Ixx", 0, 0),
    ("Ixy", 0, 1),
    ("Ixz", 0, 2),
    ("Iyy", 1, 1),
    ("Iyz", 1, 2),
    ("Izz", 2, 2),
)


def _skew(x: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -x[2], x[1]], [x[2], 0.0, -x[0]], [-x[1], x[0], 0.0]])


def spatial_inertia_derivatives(inertia: pin.Inertia) -> tuple[list[str], np.ndarray]:
    """∂I/∂p of a body's 6×6 spatial inertia for its ten parameters (closed form).

    Parameters, in order: mass, com_x, com_y, com_z, Ixx, Ixy, Ixz, Iyy, Iyz, Izz (inertia
    about the centre of mass; an off-diagonal entry moves both symmetric places).

    Returns:
        The parameter names and the derivatives, shape (10, 6, 6).
    """
    m, c = float(inertia.mass), np.array(inertia.lever, dtype=float)
    cx = _skew(c)
    out = np.zeros((10, 6, 6))
    out[0, :3, :3] = np.eye(3)
    out[0, :3, 3:], out[0, 3:, :3], out[0, 3:, 3:] = -cx, cx, -cx @ cx
    for i in range(3):
        ex = _skew(np.eye(3)[i])
        out[1 + i, :3, 3:], out[1 + i, 3:, :3] = -m * ex, m * ex
        out[1 + i, 3:, 3:] = -m * (ex @ cx + cx @ ex)
    for k, (_, a, b) in enumerate(_INERTIA_ENTRIES):
        out[4 + k, 3 + a, 3 + b] = out[4 + k, 3 + b, 3 + a] = 1.0
    names = ["mass", "com_x", "com_y", "com_z"] + [name for name, _, _ in _INERTIA_ENTRIES]
    return names, out


_UNITS = {"mass": "kg", "com": "m", "I": "kg*m^2", "offset": "m"}


def parameter_table(robot: Robot) -> list[tuple[str, str, float, str]]:
    """(body or joint, parameter, value, unit) of every parameter, in the order reported."""
    model, rows = robot.model, []
    for b, name in enumerate(body_names(robot)):
        inertia = model.inertias[b + 1]
        values = [inertia.mass, *inertia.lever]
        values += [inertia.inertia[a, c] for _, a, c in _INERTIA_ENTRIES]
        names, _ = spatial_inertia_derivatives(inertia)
        for pname, value in zip(names, values, strict=True):
            unit = _UNITS["mass" if pname == "mass" else "com" if pname[0] == "c" else "I"]
            rows.append((name, pname, float(value), unit))
        for axis, value in zip("xyz", model.jointPlacements[b + 1].translation, strict=True):
            rows.append((model.names[b + 1], f"offset_{axis}", float(value), "m"))
    for joint, start, width in dof_joint_ranges(robot):
        sliding = length_velocities(model.joints[model.getJointId(joint)])
        for k in range(width):
            label = "armature" if width == 1 else f"armature[{k}]"
            unit = "kg" if k < sliding else "kg*m^2"
            rows.append((joint, label, float(model.armature[start + k]), unit))
    return rows


def _projected_derivatives(model: pin.Model, split: BodySplit, V: np.ndarray) -> np.ndarray:
    """Vᵀ (∂M/∂p) V for every parameter, in `parameter_table`'s order: (P, k, k)."""
    nb = split.jacobian_local.shape[0]
    out = []
    local = np.einsum("bij,jk->bik", split.jacobian_local, V)  # J_b V, body frame
    world = np.einsum("bij,jk->bik", split.jacobian_world, V)
    for b in range(nb):
        _, dI = spatial_inertia_derivatives(model.inertias[b + 1])
        out.extend(np.einsum("ia,pij,jb->pab", local[b], dI, local[b]))
        subtree = split.in_subtree[b]
        outside = np.where(split.subtree_dofs[b][:, None], 0.0, V)  # J_bᴬ V: other joints only
        for e in np.eye(3):
            d = split.parent_rotation[b] @ e
            D = np.zeros((6, 6))
            D[:3, 3:] = -_skew(d)
            total = np.zeros((V.shape[1], V.shape[1]))
            for c in np.flatnonzero(subtree):
                shifted = D @ (split.jacobian_world[c] @ outside)
                half = shifted.T @ split.inertia_world[c] @ world[c]
                total += half + half.T
            out.append(total)
    for i in range(V.shape[0]):  # armature: e_i e_iᵀ
        out.append(np.outer(V[i], V[i]))
    return np.array(out)


@dataclass(frozen=True)
class Sensitivity:
    """∂κ/∂p of one parameter p at one configuration.

    Attributes:
        owner: The body (its links) or the joint the parameter belongs to.
        parameter: mass, com_x.., Ixx.., offset_x.., armature.
        value: p, in ``unit``.
        unit: Unit of p.
        dkappa: ∂κ/∂p, in 1/``unit`` (one-sided, p increasing, when ``clustered``).
        elasticity: ∂ log κ / ∂ log p = p ∂κ/∂p / κ (dimensionless; 0 when p = 0).
    """

    owner: str
    parameter: str
    value: float
    unit: str
    dkappa: float
    elasticity: float

    def to_dict(self) -> dict:
        """The record as plain Python values."""
        return asdict(self)


@dataclass(frozen=True)
class KappaSensitivities:
    """Sensitivities of κ at one configuration, ranked by |elasticity| then |∂κ/∂p|.

    Attributes:
        robot: Robot name.
        q: The configuration.
        kappa: κ = λmax/λmin of M(q) (armature included).
        lambda_min: λmin.
        lambda_max: λmax.
        clustered_min: Multiplicity of the λmin cluster (1: simple, derivatives exact).
        clustered_max: Multiplicity of the λmax cluster.
        sensitivities: One record per parameter, ranked.
        metric: ``kappa`` (of M) or ``kappa_equilibrated`` (of S = D^-1/2 M D^-1/2: then
            ``kappa``, ``lambda_min``, ``lambda_max`` and ∂κ/∂p are κ_S's).
    """

    robot: str
    q: tuple[float, ...]
    kappa: float
    lambda_min: float
    lambda_max: float
    clustered_min: int
    clustered_max: int
    sensitivities: tuple[Sensitivity, ...]
    metric: str = "kappa"

    @property
    def clustered(self) -> bool:
        """Whether λmin or λmax is clustered (then derivatives are one-sided)."""
        return self.clustered_min > 1 or self.clustered_max > 1

    def to_dict(self) -> dict:
        """The record as plain Python values."""
        out = asdict(self)
        out["q"] = list(self.q)
        out["clustered"] = self.clustered
        return out


def _clusters(w: np.ndarray, rtol: float) -> tuple[int, int]:
    floor = 100 * np.finfo(float).eps * w[-1]
    low = int(np.sum(w - w[0] <= max(rtol * w[0], floor)))
    high = int(np.sum(w[-1] - w <= max(rtol * w[-1], floor)))
    return low, high


def kappa_sensitivities(
    robot: Robot,
    q: npt.ArrayLike | None = None,
    *,
    cluster_rtol: float = CLUSTER_RTOL,
    metric: str = "kappa",
) -> KappaSensitivities:
    """∂κ/∂p and ∂ log κ/∂ log p for every parameter of `parameter_table` at ``q``.

    Args:
        robot: The robot (dense path: Pinocchio's Data is built).
        q: Configuration, length nq (default: neutral).
        cluster_rtol: Relative gap under which eigenvalues are one cluster.
        metric: ``kappa`` (κ of M) or ``kappa_equilibrated`` (κ_S, κ of S = D^-1/2 M D^-1/2;
            then ``kappa``, ``lambda_min`` and ``lambda_max`` of the result are S's).
    """
    if not 0 <= cluster_rtol < 1:
        raise InputError("cluster_rtol", "in [0, 1)", cluster_rtol)
    if metric not in METRICS:
        raise InputError("metric", f"one of {', '.join(METRICS)}", metric)
    model = robot.model
    q = pin.neutral(model) if q is None else as_configuration(robot, q)
    data = robot.new_data()
    M = check_robot_gim(robot, np.array(pin.crba(model, data, q)))
    split = body_split(robot, q, data=data)
    if metric == "kappa":
        w, vectors = np.linalg.eigh(M)
        low, high = _clusters(w, cluster_rtol)
        V = np.hstack([vectors[:, :low], vectors[:, w.size - high :]])
        projected = _projected_derivatives(model, split, V)
        d_min = np.linalg.eigvalsh(projected[:, :low, :low])[:, 0]
        d_max = np.linalg.eigvalsh(projected[:, low:, low:])[:, -1]
    else:
        w, low, high, d_min, d_max = _equilibrated_derivatives(model, split, M, cluster_rtol)
    kappa = extreme_ratio(w)
    dkappa = (d_max - kappa * d_min) / w[0]
    records = []
    for (owner, name, value, unit), dk in zip(parameter_table(robot), dkappa, strict=True):
        elasticity = value * dk / kappa if value != 0.0 else 0.0
        records.append(Sensitivity(owner, name, value, unit, float(dk), float(elasticity)))
    records.sort(key=lambda r: (-abs(r.elasticity), -abs(r.dkappa)))
    return KappaSensitivities(
        robot=robot.name,
        q=tuple(float(x) for x in q),
        kappa=kappa,
        lambda_min=float(w[0]),
        lambda_max=float(w[-1]),
        clustered_min=low,
        clustered_max=high,
        sensitivities=tuple(records),
        metric=metric,
    )


def _equilibrated_derivatives(model, split: BodySplit, M: np.ndarray, cluster_rtol: float):
    """Spectrum of S = D^-1/2 M D^-1/2 and ∂⁺μmin, ∂⁺μmax of S for every parameter.

    For an eigenvector u of S (eigenvalue μ) and v = D^-1/2 u,
    ``uᵀ ∂S u = vᵀ ∂M v − μ Σ_i v_i² ∂M_ii`` (∂D = diag ∂M and S u = μ u); over a cluster the
    same holds blockwise, ``Vᵀ ∂M V − μ Vᵀ diag(∂M) V``.
    """
    r = 1.0 / np.sqrt(np.diag(M))
    w, vectors = np.linalg.eigh(M * np.outer(r, r))
    low, high = _clusters(w, cluster_rtol)
    V = r[:, None] * np.hstack([vectors[:, :low], vectors[:, w.size - high :]])
    k, n = V.shape[1], M.shape[0]
    projected = _projected_derivatives(model, split, np.hstack([V, np.eye(n)]))
    diagonal = np.diagonal(projected[:, k:, k:], axis1=1, axis2=2)  # ∂M_ii, (P, n)
    scaled = np.einsum("pi,ia,ib->pab", diagonal, V, V)
    block = projected[:, :k, :k]
    d_min = np.linalg.eigvalsh(block[:, :low, :low] - w[0] * scaled[:, :low, :low])[:, 0]
    d_max = np.linalg.eigvalsh(block[:, low:, low:] - w[-1] * scaled[:, low:, low:])[:, -1]
    return w, low, high, d_min, d_max
