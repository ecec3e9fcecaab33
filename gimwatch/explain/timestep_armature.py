"""The least joint armature that makes a timestep stable at given configurations, and its price.

Armature A = diag(a) adds to M. For the semi-implicit integrators (MuJoCo's ``Euler``,
``implicitfast``, ``implicit``; gimwatch's ``semi-implicit-euler``) an eigenvalue z of the step
map satisfies ``M(z−1)² + h·D(z−1)z + h·C(z−1) + h²K z = 0`` (D: damping taken implicitly, C:
explicitly). Taking φᴴ(·)φ, a root on the unit circle other than ±1 needs φᴴCφ + φᴴDφ = 0, an
undamped mode, which stays marginal; so stability is lost where z = −1, where

    S(h) = 4M + 2h·D − 2h·C − h²K

stops being positive definite (K is symmetric: servo, spring and gravity stiffness are the
Hessian of an energy). The one-joint cases are the closed forms h²k < 4m + 2hd − 2hc. With
K ⪰ 0, S is concave in h, so S(H) + 4A ⪰ 0 makes every h ≤ H stable: a **linear matrix
inequality in a**, solved by `gimwatch.explain.armature.least_total`'s certified cutting planes
(per joint, least total, with a lower bound) or in closed form (uniform: a = max(0, −λmin(S)/4)).

``RK4`` has no such inequality: a uniform a is found by bisection on h*(M + aI) ≥ H, and each
answer is certified by recomputing h* with the armature applied (`max_stable_timestep_after_s`).

The price: added inertia as a percentage of each joint's diagonal of M, the relative change of
q̈ under gravity alone, and each servo's frequency √(k_i / M_ii) before and after.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypedDict, Unpack

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.explain.armature import least_total
from gimwatch.model.robots import Robot
from gimwatch.stability.analysis import held_systems
from gimwatch.stability.linear_system import LinearSystem
from gimwatch.stability.step_maps import EXPLICIT_DAMPING, check_integrator
from gimwatch.stability.timestep import max_stable_timestep

__all__ = ["HoldOptions", "TimestepArmaturePlan", "stability_matrix", "timestep_armature"]

#: Bisection steps of RK4's uniform armature (relative width 2⁻⁴⁰ of the bracket).
BISECTIONS = 60


@dataclass(frozen=True)
class TimestepArmaturePlan:
    """Armature to add so that ``integrator`` is stable at ``timestep_s``, and what it does.

    Attributes:
        robot: Robot name.
        integrator: The integrator.
        timestep_s: The timestep to make stable, s.
        per_joint: One value per coordinate (least total) instead of one uniform value.
        method: ``"LMI, cutting planes"``, ``"LMI, closed form"`` or ``"bisection"``.
        dof_names: Names of the coordinates.
        armature: Armature to add per coordinate (kg·m² revolute, kg prismatic).
        lower_bound: A lower bound on the least total (the total itself when exact).
        h_star_before_s: h* at each configuration without the armature.
        h_star_after_s: h* at each configuration with it (the certificate: each ≥ timestep_s).
        inertia_percent: Added inertia as % of the coordinate's smallest diagonal of M.
        qdd_change: Relative change of q̈ under gravity at each configuration.
        servo_frequency_before_rad_s: √(k_i / M_ii) at the first configuration (NaN unheld).
        servo_frequency_after_rad_s: The same with the armature.
    """

    robot: str
    integrator: str
    timestep_s: float
    per_joint: bool
    method: str
    dof_names: tuple[str, ...]
    armature: tuple[float, ...]
    lower_bound: float
    h_star_before_s: tuple[float, ...]
    h_star_after_s: tuple[float, ...]
    inertia_percent: tuple[float, ...]
    qdd_change: tuple[float, ...]
    servo_frequency_before_rad_s: tuple[float, ...]
    servo_frequency_after_rad_s: tuple[float, ...]

    @property
    def total(self) -> float:
        """Σ a_i."""
        return float(sum(self.armature))

    def to_dict(self) -> dict:
        """The plan as plain Python values (the same ``armature`` dict as the κ target's)."""

        def per_dof(values):
            return dict(zip(self.dof_names, (_finite(v) for v in values), strict=True))

        return {
            "robot": self.robot,
            "integrator": self.integrator,
            "timestep_s": self.timestep_s,
            "per_joint": self.per_joint,
            "method": self.method,
            "armature": dict(zip(self.dof_names, self.armature, strict=True)),
            "total": self.total,
            "lower_bound": self.lower_bound,
            "max_stable_timestep_before_s": [_finite(h) for h in self.h_star_before_s],
            "max_stable_timestep_after_s": [_finite(h) for h in self.h_star_after_s],
            "inertia_percent": per_dof(self.inertia_percent),
            "qdd_change": list(self.qdd_change),
            "servo_frequency_rad_s": {
                name: {"before": _finite(b), "after": _finite(a)}
                for name, b, a in zip(
                    self.dof_names,
                    self.servo_frequency_before_rad_s,
                    self.servo_frequency_after_rad_s,
                    strict=True,
                )
            },
        }


def _finite(value: float) -> float | None:
    return float(value) if np.isfinite(value) else None


def stability_matrix(system: LinearSystem, integrator: str, h: float) -> np.ndarray:
    """S(h) = 4M + 2h·D_implicit − 2h·C_explicit − h²K, symmetrised (see the module)."""
    explicit = EXPLICIT_DAMPING[check_integrator(integrator)]
    if explicit == "actuator":
        implicit, explicit_c = system.joint_damping, system.explicit_damping
    elif explicit == "none":
        implicit, explicit_c = system.damping, np.zeros_like(system.mass)
    else:
        implicit, explicit_c = np.zeros_like(system.mass), system.damping
    S = 4 * system.mass + 2 * h * implicit - 2 * h * explicit_c - h * h * system.stiffness
    return 0.5 * (S + S.T)


def _lmi(systems, integrator, h, per_joint, rtol):
    Ss = [stability_matrix(s, integrator, h) for s in systems]
    n = Ss[0].shape[0]

    def lift(a):
        worst = max(-np.linalg.eigvalsh(S + 4 * np.diag(a))[0] for S in Ss)
        return max(0.0, worst / 4.0)

    if not per_joint:
        value = lift(np.zeros(n))
        return np.full(n, value), n * value, "LMI, closed form"

    def cuts(a):
        found = []
        for S in Ss:
            w, vectors = np.linalg.eigh(S + 4 * np.diag(a))
            if w[0] < 0:  # g(a) = −λmin(S + 4A), ∂g/∂a_i = −4 w_i²
                found.append((-w[0], -4 * vectors[:, 0] ** 2))
        return found

    added, lower, _ = least_total(cuts, lift, n, rtol)
    return added, lower, "LMI, cutting planes"


def _bisected(systems, integrator, h):
    def stable(value):
        return all(
            max_stable_timestep(s.with_mass(np.full(s.n, value)), integrator) >= h for s in systems
        )

    if stable(0.0):
        return 0.0
    high = max(float(np.max(np.diag(s.mass))) for s in systems) * 1e-3
    while not stable(high):
        high *= 4.0
        if high > 1e12:
            raise InputError("timestep_s", f"reachable by armature with {integrator}", h)
    low = 0.0
    for _ in range(BISECTIONS):
        middle = 0.5 * (low + high)
        low, high = (low, middle) if stable(middle) else (middle, high)
    return high


class HoldOptions(TypedDict, total=False):
    """How the robot is held: the keywords `timestep_armature` passes on to ``held_systems``.

    Attributes:
        kp: Servo stiffness (one number or one per coordinate) for robots without actuators.
        kd: Servo damping, explicit.
        gravity: Include gravity's stiffness (default True).
        keyframe: An MJCF keyframe's name to hold.
    """

    kp: float | Sequence[float] | None
    kd: float | Sequence[float] | None
    gravity: bool
    keyframe: str | None


def timestep_armature(
    robot: Robot,
    timestep_s: float,
    integrator: str,
    configurations: npt.ArrayLike | None = None,
    *,
    per_joint: bool = False,
    rtol: float = 1e-6,
    margin: float = 1e-6,
    **hold: Unpack[HoldOptions],
) -> TimestepArmaturePlan:
    """The least armature to add so that ``integrator`` is stable at ``timestep_s``.

    Args:
        robot: A fixed-base robot with servos (an MJCF file's, or ``kp``/``kd``).
        timestep_s: The timestep to make stable, s.
        integrator: A name from `gimwatch.stability.step_maps.INTEGRATORS`.
        configurations: Held configurations (K, nq); default: keyframe 0, qpos0 or neutral.
        per_joint: One value per coordinate, least total (cutting planes on the LMI).
        rtol: Relative optimality gap of the cutting planes.
        margin: Relative amount the answer is raised so that float64 meets the inequality.
        **hold: How the robot is held (`HoldOptions`, passed on to
            `gimwatch.stability.analysis.held_systems`): ``kp`` (servo stiffness, one number
            or one per coordinate, for robots without actuators), ``kd`` (servo damping,
            explicit), ``gravity`` (include gravity's stiffness, default True), ``keyframe``
            (an MJCF keyframe's name to hold).

    Raises:
        InputError: A timestep ≤ 0, an unknown integrator, per_joint with RK4, bad servos.
    """
    if not (np.isfinite(timestep_s) and timestep_s > 0):
        raise InputError("timestep_s", "a finite number > 0", timestep_s)
    check_integrator(integrator)
    if per_joint and integrator == "RK4":
        raise InputError("per_joint", "False with RK4 (no LMI: one uniform value, bisected)", True)
    qs, systems, servos = held_systems(robot, configurations, **hold)
    if integrator == "RK4":
        value = _bisected(systems, integrator, timestep_s)
        added, lower, method = np.full(robot.nv, value), robot.nv * value, "bisection"
    else:
        added, lower, method = _lmi(systems, integrator, timestep_s, per_joint, rtol)
    added = added * (1.0 + margin)
    before = tuple(max_stable_timestep(s, integrator) for s in systems)
    after = tuple(max_stable_timestep(s.with_mass(added), integrator) for s in systems)
    diagonals = np.array([np.diag(s.mass) for s in systems])
    first = diagonals[0]
    held = servos.stiffness > 0
    freq_before = np.where(held, np.sqrt(np.where(held, servos.stiffness, 0) / first), np.nan)
    freq_after = np.where(
        held, np.sqrt(np.where(held, servos.stiffness, 0) / (first + added)), np.nan
    )
    return TimestepArmaturePlan(
        robot=robot.name,
        integrator=integrator,
        timestep_s=float(timestep_s),
        per_joint=per_joint,
        method=method,
        dof_names=robot.dof_names,
        armature=tuple(float(x) for x in added),
        lower_bound=float(lower),
        h_star_before_s=before,
        h_star_after_s=after,
        inertia_percent=tuple(float(x) for x in 100 * added / diagonals.min(axis=0)),
        qdd_change=_gravity_change(robot, qs, systems, added),
        servo_frequency_before_rad_s=tuple(float(x) for x in freq_before),
        servo_frequency_after_rad_s=tuple(float(x) for x in freq_after),
    )


def _gravity_change(robot, qs, systems, added) -> tuple[float, ...]:
    """‖(M + A)⁻¹g − M⁻¹g‖ / ‖M⁻¹g‖ at each configuration (Pinocchio's g)."""
    model, data = robot.model, robot.new_data()
    change = []
    for q, system in zip(qs, systems, strict=True):
        g = pin.computeGeneralizedGravity(model, data, q)
        qdd = np.linalg.solve(system.mass, -g)
        qdd_armed = np.linalg.solve(system.mass + np.diag(added), -g)
        scale = np.linalg.norm(qdd)
        change.append(float(np.linalg.norm(qdd_armed - qdd) / scale) if scale > 0 else 0.0)
    return tuple(change)
