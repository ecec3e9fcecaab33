"""Will it explode? h*, the verdict at a timestep and the critical mode, robot by robot.

`stability` takes a robot (or its spec), its servos (an MJCF file's own actuators, or ``kp``
and ``kd`` gains), the configurations they hold (keyframe 0, else ``qpos0``/neutral, or given)
and the integrators asked (default: the model's own; MuJoCo's ``Euler`` for robots without
one), and returns one `StabilityRecord` per configuration and integrator. The timestep judged
is ``timestep_s`` if given, else the model's ``<option timestep>`` (MuJoCo's default 2 ms for
robots without one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TypedDict, Unpack

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.errors import InputError
from gimwatch.model.configuration import user_configuration
from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robot_spec import RobotSpec
from gimwatch.model.robots import Robot, load_robot
from gimwatch.stability.linear_system import LinearSystem, linearise
from gimwatch.stability.servos import Servos, gain_servos, mjcf_servos
from gimwatch.stability.step_maps import check_integrator
from gimwatch.stability.timestep import critical_mode, max_stable_timestep

__all__ = ["DEFAULT_TIMESTEP_S", "StabilityRecord", "held_systems", "stability"]

#: MuJoCo's default ``<option timestep>``, judged for robots that state none.
DEFAULT_TIMESTEP_S = 0.002


@dataclass(frozen=True)
class StabilityRecord:
    """Whether one integrator at one timestep keeps one held configuration bounded.

    Attributes:
        robot: Robot name.
        config: Index of the configuration.
        q: The held configuration (Pinocchio's q; MuJoCo's qpos for MJCF).
        integrator: The integrator's name (MuJoCo's, or gimwatch's scene integrator).
        max_stable_timestep_s: h*, s (0: the held configuration is itself unstable; ∞: stable
            at every timestep scanned).
        timestep_s: The timestep judged, s.
        stable: Whether timestep_s ≤ h*.
        margin: timestep_s / h* (below 1 is stable).
        dof_names: Names of the coordinates.
        participation: The critical mode's share of each coordinate (empty when h* is 0 or ∞).
        frequency_rad_s: The critical mode's undamped frequency, rad/s (NaN without one).
        limited_by: ``"stiffness"``, ``"explicit damping"``, ``"unstable at rest"`` or ``""``.
        not_modelled: What the robot has that the linear model leaves out.
    """

    robot: str
    config: int
    q: tuple[float, ...]
    integrator: str
    max_stable_timestep_s: float
    timestep_s: float
    stable: bool
    margin: float
    dof_names: tuple[str, ...]
    participation: tuple[float, ...]
    frequency_rad_s: float
    limited_by: str
    not_modelled: tuple[str, ...]

    @property
    def critical_dof(self) -> str:
        """The coordinate that carries most of the critical mode ("" without one)."""
        if not self.participation:
            return ""
        return self.dof_names[int(np.argmax(self.participation))]

    def to_dict(self) -> dict:
        """The record as plain Python values (h* = ∞ as None)."""
        h = self.max_stable_timestep_s
        return {
            "robot": self.robot,
            "config": self.config,
            "q": list(self.q),
            "integrator": self.integrator,
            "max_stable_timestep_s": h if np.isfinite(h) else None,
            "timestep_s": self.timestep_s,
            "stable": self.stable,
            "margin": self.margin,
            "critical_mode": {
                "participation": dict(zip(self.dof_names, self.participation, strict=False)),
                "dof": self.critical_dof,
                "frequency_rad_s": self.frequency_rad_s,
                "limited_by": self.limited_by,
            },
            "not_modelled": list(self.not_modelled),
        }


def _mjcf_model(robot: Robot):
    from gimwatch.model.mjcf_compiled import compile_mjcf

    return compile_mjcf(robot.source)


def default_configurations(robot: Robot, mj_model=None, keyframe: str | None = None) -> np.ndarray:
    """Keyframe ``keyframe`` (by name), else keyframe 0, else qpos0 (MJCF) or neutral, (K, nq)."""
    if mj_model is None:
        if keyframe is not None:
            raise InputError("keyframe", "given only for an MJCF file", keyframe)
        return pin.neutral(robot.model)[None, :]
    if keyframe is not None:
        names = [mj_model.key(k).name for k in range(mj_model.nkey)]
        if keyframe not in names:
            shown = ", ".join(repr(n) for n in names) or "none"
            raise InputError("keyframe", f"a keyframe of {robot.source} ({shown})", keyframe)
        qpos = mj_model.key_qpos[names.index(keyframe)]
    else:
        qpos = mj_model.key_qpos[0] if mj_model.nkey else mj_model.qpos0
    # MuJoCo's qpos to Pinocchio's q (quaternions (w, x, y, z) -> (x, y, z, w))
    return user_configuration(robot, np.array(qpos, dtype=float), key="keyframe")[None, :]


def held_controls(mj_model, q: np.ndarray) -> np.ndarray:
    """The controls that hold q: ``gear·q`` for a position servo (a bias with b1 ≠ 0), else 0."""
    joints = np.clip(mj_model.actuator_trnid[:, 0], 0, max(mj_model.njnt - 1, 0))
    ctrl = mj_model.actuator_gear[:, 0] * q[mj_model.jnt_qposadr[joints]]
    return np.where(mj_model.actuator_biasprm[:, 1] != 0, ctrl, 0.0)


def held_systems(
    robot: Robot,
    configurations: npt.ArrayLike | None = None,
    *,
    kp: float | Sequence[float] | None = None,
    kd: float | Sequence[float] | None = None,
    gravity: bool = True,
    keyframe: str | None = None,
) -> tuple[np.ndarray, list[LinearSystem], Servos]:
    """The held configurations (K, nq), the linear system at each, and the servos.

    MJCF files use their own actuators (``kp``/``kd`` replace them when given); other robots
    need ``kp``. An MJCF servo holds q: its control is `held_controls`.

    Raises:
        InputError: No actuators and no gains; bad gains; an unknown keyframe.
    """
    mj_model = _mjcf_model(robot) if robot.mujoco_joints and not robot.mjcf_body else None
    if robot.mjcf_body:
        raise InputError(
            "body", "left out for stability (MuJoCo's model is the whole file)", robot.mjcf_body
        )
    if configurations is None:
        qs = default_configurations(robot, mj_model, keyframe)
    else:
        if keyframe is not None:
            raise InputError("keyframe", "left out when configurations are given", keyframe)
        qs = np.atleast_2d(np.asarray(configurations, dtype=float))
    qs = np.array([as_configuration(robot, q) for q in qs])
    use_gains = kp is not None or kd is not None
    if mj_model is None and not use_gains:
        raise InputError("kp", f"given: {robot.name} has no actuators of its own", "none")
    if mj_model is not None and not use_gains and mj_model.nu == 0:
        raise InputError("kp", f"given: {robot.source} has no actuators", "none")
    model = pin.Model(robot.model)
    if mj_model is not None:
        model.gravity.linear = np.array(mj_model.opt.gravity)
    data = model.createData()
    systems: list[LinearSystem] = []
    servos: Servos | None = None
    for q in qs:
        if use_gains:
            servos = gain_servos(robot, 0.0 if kp is None else kp, kd)
            if mj_model is not None:  # the file's timestep and integrator still apply
                own = mjcf_servos(robot, mj_model, np.zeros(mj_model.nu))
                servos = Servos(
                    servos.stiffness,
                    servos.explicit_damping,
                    own.joint_damping,
                    servos.actuated,
                    own.timestep_s,
                    own.integrator,
                    own.not_modelled,
                )
        else:
            ctrl = held_controls(mj_model, q)
            servos = mjcf_servos(robot, mj_model, ctrl)
        systems.append(linearise(model, servos, q, gravity=gravity, data=data, source=robot.source))
    if servos is None:  # an empty (0, nq) array of configurations
        raise InputError("configurations", "at least one configuration", "none")
    return qs, systems, servos


class HeldOptions(TypedDict, total=False):
    """How the robot is held: the keyword options of `held_systems`, passed on by `stability`."""

    kp: float | Sequence[float] | None
    kd: float | Sequence[float] | None
    gravity: bool
    keyframe: str | None


def stability(
    robot: Robot | RobotSpec | str,
    configurations: npt.ArrayLike | None = None,
    *,
    integrators: Sequence[str] | None = None,
    timestep_s: float | None = None,
    **held: Unpack[HeldOptions],
) -> list[StabilityRecord]:
    """h*, the verdict at the timestep and the critical mode, per configuration and integrator.

    Args:
        robot: A `Robot`, its `RobotSpec`, or its text (chain:N, a URDF/MJCF path, an
            example-robot-data name), parsed and loaded once.
        configurations: Held configurations (K, nq); default: keyframe 0, qpos0 or neutral.
        integrators: Names from `gimwatch.stability.step_maps.INTEGRATORS`; default: the
            model's own (``Euler`` without one).
        timestep_s: The timestep judged; default: the model's (2 ms without one).
        **held: How the robot is held, as in `held_systems`: ``gravity`` (default True:
            include gravity's stiffness ∂g/∂q), ``kp`` (servo stiffness, one number or one
            per coordinate, instead of the file's actuators), ``kd`` (servo damping,
            explicit, one number or one per coordinate), ``keyframe`` (an MJCF keyframe's
            name to hold).

    Raises:
        InputError: An unknown integrator or keyframe, a timestep ≤ 0, no servos, bad gains.
    """
    if not isinstance(robot, Robot):  # a spec: parsed and loaded once
        robot = load_robot(robot)
    if timestep_s is not None and not (np.isfinite(timestep_s) and timestep_s > 0):
        raise InputError("timestep_s", "a finite number > 0", timestep_s)
    names = list(integrators) if integrators else []
    for name in names:
        check_integrator(name)
    qs, systems, servos = held_systems(robot, configurations, **held)
    names = names or [servos.integrator or "Euler"]
    h = timestep_s if timestep_s is not None else servos.timestep_s or DEFAULT_TIMESTEP_S
    records = []
    for index, (q, system) in enumerate(zip(qs, systems, strict=True)):
        for name in names:
            records.append(_record(robot, index, q, system, servos, name, float(h)))
    return records


def _record(robot, index, q, system, servos, name, h) -> StabilityRecord:
    h_star = max_stable_timestep(system, name)
    mode = critical_mode(system, name, h_star)
    limited = mode.limited_by if mode else ("unstable at rest" if h_star == 0 else "")
    return StabilityRecord(
        robot=robot.name,
        config=index,
        q=tuple(float(x) for x in q),
        integrator=name,
        max_stable_timestep_s=h_star,
        timestep_s=h,
        stable=bool(h <= h_star),
        margin=float(h / h_star) if h_star > 0 else float("inf"),
        dof_names=robot.dof_names,
        participation=tuple(float(p) for p in mode.participation) if mode else (),
        frequency_rad_s=mode.frequency_rad_s if mode else float("nan"),
        limited_by=limited,
        not_modelled=servos.not_modelled,
    )
