"""MuJoCo as a peer simulator: the same URDF, the same physics, its own integrators.

MuJoCo (optional extra ``gimwatch[peers]``) reads URDF through
`mujoco.MjModel.from_xml_string`. The robot's URDF text is passed unchanged except
for one ``<mujoco><compiler .../></mujoco>`` block after the ``<robot>`` tag:

* ``discardvisual`` and ``fusestatic="false"`` keep the kinematic tree as the URDF has it;
* ``boundinertia`` = `INERTIA_FLOOR` lifts the slender rods' zero axial inertia
  (I_xx = 0, which MuJoCo rejects) to 1e-12 kg·m²; rotating about z only, the planar
  chains never feel it (the mass-matrix check below shows it).

Then, on the compiled model: constraints, contacts, joint limits, springs and dampers off;
joint armature and damping zero; gravity set to the scene's vector. `mass_matrix`
gives ``mj_fullM`` after ``mj_forward``, to be compared with Pinocchio's CRBA before any
timing. `simulate` steps with ``mj_step(m, d, nstep)`` between samples and evaluates
the energy (``mj_energyPos`` + ``mj_energyVel``) at the samples only.
"""

from __future__ import annotations

import re
import time
from dataclasses import dataclass

import numpy as np

from gimwatch.errors import InputError

__all__ = [
    "INERTIA_FLOOR",
    "METHODS",
    "PeerRun",
    "available",
    "load_model",
    "mass_matrix",
    "simulate",
]

INERTIA_FLOOR = 1e-12
#: gimwatch's fixed-step method names -> MuJoCo integrator names.
METHODS = {"RK4": "mjINT_RK4", "semi-implicit-euler": "mjINT_EULER"}
_COMPILER = (
    f'<mujoco><compiler discardvisual="true" fusestatic="false" '
    f'boundinertia="{INERTIA_FLOOR:g}" angle="radian"/></mujoco>'
)


def available() -> bool:
    """Whether MuJoCo can be imported (the ``peers`` extra is installed)."""
    try:
        import mujoco  # noqa: F401
    except ImportError:
        return False
    return True


def load_model(urdf_xml: str, gravity: np.ndarray):
    """Compile ``urdf_xml`` in MuJoCo with limits, contacts, damping and armature off.

    Args:
        urdf_xml: The robot's URDF text (as Pinocchio loaded it).
        gravity: Gravity vector (m/s²), in the chain's plane for the paper's chains.

    Returns:
        The ``mujoco.MjModel``.

    Raises:
        InputError: The text has no ``<robot>`` tag.
    """
    import mujoco

    xml, count = re.subn(r"(<robot\b[^>]*>)", lambda m: m.group(1) + _COMPILER, urdf_xml, count=1)
    if count != 1:
        raise InputError("urdf_xml", "URDF text with a <robot> tag", "no <robot> tag")
    model = mujoco.MjModel.from_xml_string(xml)
    flags = mujoco.mjtDisableBit
    for flag in ("CONSTRAINT", "CONTACT", "LIMIT", "SPRING", "DAMPER"):
        model.opt.disableflags |= int(getattr(flags, f"mjDSBL_{flag}"))
    model.jnt_limited[:] = 0
    model.dof_armature[:] = 0.0
    model.dof_damping[:] = 0.0
    model.dof_frictionloss[:] = 0.0
    model.opt.gravity[:] = np.asarray(gravity, dtype=float)
    return model


def mass_matrix(model, q: np.ndarray) -> np.ndarray:
    """MuJoCo's dense M(q): ``mj_fullM`` after ``mj_forward`` at ``q`` (zero velocity)."""
    from gimwatch.model.mujoco_model import mass_matrix as mujoco_mass_matrix

    return mujoco_mass_matrix(model, q)


@dataclass(frozen=True)
class PeerRun:
    """One MuJoCo run: final state, energy drift, wall time, steps.

    Attributes:
        q: Final configuration (rad).
        v: Final velocity (rad/s).
        energy_drift: max_t |E(t) − E(0)| / max(|E(0)|, max_t KE(t)), at the samples.
        wall_time_s: Wall time of the stepping loop, samples included.
        steps: Steps taken (RK4 evaluates the dynamics 4 times per step, Euler once).
    """

    q: np.ndarray
    v: np.ndarray
    energy_drift: float
    wall_time_s: float
    steps: int


def simulate(
    model,
    q0: np.ndarray,
    v0: np.ndarray,
    *,
    method: str,
    dt: float,
    duration_s: float,
    sample_s: float,
) -> PeerRun:
    """Integrate from (q0, v0) with MuJoCo's ``method`` at step ``dt`` for ``duration_s``.

    Args:
        model: From `load_model` (its timestep and integrator are set here).
        q0: Initial configuration.
        v0: Initial velocity.
        method: A key of `METHODS`.
        dt: Step (s); ``sample_s`` must be a multiple of it.
        duration_s: Length of the run (s), a multiple of ``sample_s``.
        sample_s: Energy is evaluated every ``sample_s`` seconds.
    """
    import mujoco

    model.opt.timestep = dt
    model.opt.integrator = int(getattr(mujoco.mjtIntegrator, METHODS[method]))
    data = mujoco.MjData(model)
    data.qpos[:], data.qvel[:] = q0, v0
    per_sample = max(1, round(sample_s / dt))
    samples = round(duration_s / (per_sample * dt))

    def energy() -> tuple[float, float]:
        mujoco.mj_forward(model, data)
        mujoco.mj_energyPos(model, data)
        mujoco.mj_energyVel(model, data)
        return float(data.energy[0] + data.energy[1]), float(data.energy[1])

    start = time.perf_counter()
    energies = [energy()]
    for _ in range(samples):
        mujoco.mj_step(model, data, per_sample)
        energies.append(energy())
    wall = time.perf_counter() - start
    total = np.array([e[0] for e in energies])
    scale = max(abs(total[0]), max(e[1] for e in energies), 1e-300)
    return PeerRun(
        q=data.qpos.copy(),
        v=data.qvel.copy(),
        energy_drift=float(np.max(np.abs(total - total[0])) / scale),
        wall_time_s=wall,
        steps=samples * per_sample,
    )
