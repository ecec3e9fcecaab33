"""One step of each integrator on the linearised robot: the 2n × 2n map x_{k+1} = Φ(h) x_k.

On x = (q, v) and M ẍ + C ẋ + K x = 0 (`gimwatch.stability.linear_system`), with
D_imp the damping an integrator takes implicitly and G = (M + h·D_imp)⁻¹:

    a = −G (K q + C v),   v' = v + h a,   q' = q + h v'      (semi-implicit: q uses the new v)

* ``Euler`` (MuJoCo): D_imp = joint damping (``mj_Euler`` factors M + h·diag(dof_damping));
  actuator damping stays explicit.
* ``implicitfast`` / ``implicit`` (MuJoCo): D_imp = C = −∂f/∂v, actuator and joint damping
  (Coriolis' derivative, which only ``implicit`` adds, vanishes at rest).
* ``semi-implicit-euler`` (gimwatch's scene integrator): D_imp = 0, every damping explicit.
* ``RK4`` (MuJoCo's and gimwatch's, the same classic scheme): Φ = Σ_{k≤4} (hA)^k / k!.

The integrators are declared once, in `INTEGRATORS`; the CLI's choices read it.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from gimwatch.errors import InputError
from gimwatch.stability.linear_system import LinearSystem

__all__ = ["EXPLICIT_DAMPING", "INTEGRATORS", "check_integrator", "step_map"]


def _semi_implicit(system: LinearSystem, h: float, implicit_damping: np.ndarray) -> np.ndarray:
    n = system.n
    inverse = np.linalg.inv(system.mass + h * implicit_damping)
    gk, gc = inverse @ system.stiffness, inverse @ system.damping
    eye = np.eye(n)
    v_row = np.hstack([-h * gk, eye - h * gc])  # v' in terms of (q, v)
    q_row = np.hstack([eye, np.zeros((n, n))]) + h * v_row
    return np.vstack([q_row, v_row])


def _euler(system: LinearSystem, h: float) -> np.ndarray:
    return _semi_implicit(system, h, system.joint_damping)


def _implicit(system: LinearSystem, h: float) -> np.ndarray:
    return _semi_implicit(system, h, system.damping)


def _explicit_damping(system: LinearSystem, h: float) -> np.ndarray:
    return _semi_implicit(system, h, np.zeros_like(system.mass))


def _rk4(system: LinearSystem, h: float) -> np.ndarray:
    ha = h * system.state_matrix()
    term, total = np.eye(2 * system.n), np.eye(2 * system.n)
    for k in range(1, 5):
        term = term @ ha / k
        total = total + term
    return total


#: Integrator name -> one-step map Φ(system, h). MuJoCo's names, then gimwatch's own.
INTEGRATORS: dict[str, Callable[[LinearSystem, float], np.ndarray]] = {
    "Euler": _euler,
    "implicitfast": _implicit,
    "implicit": _implicit,
    "RK4": _rk4,
    "semi-implicit-euler": _explicit_damping,
}

#: Which damping each integrator takes explicitly: "actuator", "all" or "none".
EXPLICIT_DAMPING = {
    "Euler": "actuator",
    "implicitfast": "none",
    "implicit": "none",
    "RK4": "all",
    "semi-implicit-euler": "all",
}


def check_integrator(name: str) -> str:
    """``name`` if it is a known integrator, else one line listing them."""
    if name not in INTEGRATORS:
        raise InputError("integrator", f"one of {', '.join(INTEGRATORS)}", name)
    return name


def step_map(system: LinearSystem, integrator: str, h: float) -> np.ndarray:
    """Φ(h), the integrator's one-step map on (q, v), shape 2n × 2n."""
    return INTEGRATORS[check_integrator(integrator)](system, h)
