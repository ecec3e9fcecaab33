"""MuJoCo as the judge of stability: does a servoed robot, kicked at rest, diverge at timestep h?

The acceptance test of issue 36: keyframe 0 held by the servos (ctrl = the keyframe's qpos
times each position servo's gear, 0 for a velocity servo), a 1e-9 velocity kick on every DoF,
contacts, constraints, joint limits and gravity disabled; divergence is |qpos − qpos_held|
(or h·|qvel|) growing past 1e-5 (1e4 times the kick) within 3 s of simulated time. Short
steps are capped at `MAX_STEPS` steps (a diverging run at h near h* crosses 1e-5 within a few
thousand steps), and long steps get at least `MIN_STEPS`, because near h* ρ is barely above 1
and 3 s may be only a few steps.
"""

from __future__ import annotations

import mujoco
import numpy as np

MAX_STEPS, MIN_STEPS = 20_000, 10_000
KICK, GROWTH = 1e-9, 1e-5
INTEGRATORS = {"Euler": 0, "RK4": 1, "implicit": 2, "implicitfast": 3}


def load(path: str, integrator: str | None = None) -> mujoco.MjModel:
    """MuJoCo's model of ``path`` with the flags of the test (and another integrator if given)."""
    model = mujoco.MjModel.from_xml_path(str(path))
    flags = mujoco.mjtDisableBit
    model.opt.disableflags |= (
        flags.mjDSBL_CONTACT | flags.mjDSBL_CONSTRAINT | flags.mjDSBL_LIMIT | flags.mjDSBL_GRAVITY
    )
    if integrator is not None:
        model.opt.integrator = INTEGRATORS[integrator]
    return model


def diverges(model: mujoco.MjModel, h: float | None = None, *, duration_s: float = 3.0) -> bool:
    """Whether the kicked robot grows past 1e-5 within 3 s at timestep h (the model's if None)."""
    if h is not None:
        model.opt.timestep = h
    h = model.opt.timestep
    data = mujoco.MjData(model)
    mujoco.mj_resetDataKeyframe(model, data, 0)
    held = data.qpos.copy()
    joints = model.actuator_trnid[:, 0]
    data.ctrl[:] = model.actuator_gear[:, 0] * held[model.jnt_qposadr[joints]]
    data.ctrl[model.actuator_biasprm[:, 1] == 0] = 0.0  # velocity servos hold v = 0
    data.qvel[:] = KICK
    steps = min(max(int(np.ceil(duration_s / h)), MIN_STEPS), MAX_STEPS)
    for _ in range(steps):
        mujoco.mj_step(model, data)
        if not (
            np.all(np.isfinite(data.qpos))
            and np.max(np.abs(data.qpos - held)) <= GROWTH
            and np.max(np.abs(data.qvel)) <= GROWTH / h
        ):
            return True
    return False


def threshold(model: mujoco.MjModel, low: float, high: float, rtol: float = 5e-3) -> tuple:
    """MuJoCo's divergence threshold bracketed in (low, high] by bisection on the timestep."""
    assert not diverges(model, low) and diverges(model, high), (low, high)
    while high / low > 1 + rtol:
        middle = np.sqrt(low * high)
        if diverges(model, middle):
            high = middle
        else:
            low = middle
    return low, high
