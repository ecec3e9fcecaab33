"""The effects a scene may declare, one small class each, in a registry keyed by scene name.

Every effect but gravity contributes a generalized force τ_e(t, q, v) (length nv) to the
equation of motion ``M(q) a + C(q, v) v + g(q) = Σ τ_e``. Gravity instead sets the gravity
vector the dynamics backend uses, so an undeclared gravity is a zero vector and no
gravity term is ever formed. Effects that are not declared are not instantiated at all.

* ``gravity`` — ``g(q)`` through the backend (Pinocchio's ``model.gravity``).
* ``damping`` — viscous joint damping ``τ = -c ⊙ v``.
* ``spring`` — joint springs ``τ = -k ⊙ (q - q_rest)``, potential ``½ Σ k (q - q_rest)²``.
* ``torque`` — applied joint torques: ``constant`` (``τ = τ₀``), ``sinusoid``
  (``τ = τ₀ + A sin(2π f t + φ)``) or ``pd`` (``τ = k_p (q* - q) - k_d v``).
* ``wrench`` — a constant wrench (force, torque) on a named link, mapped to joint space
  as ``τ = Jᵀ w`` with Pinocchio's frame Jacobian (``LOCAL`` or ``LOCAL_WORLD_ALIGNED``).
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pinocchio as pin

from gimwatch.errors import SceneError
from gimwatch.model.robots import Robot

__all__ = ["EFFECTS", "Effect", "build_effects", "joint_vector"]


def joint_vector(
    robot: Robot,
    values: Any,
    *,
    source: str,
    key: str,
    space: str = "v",
    default: np.ndarray | float = 0.0,
) -> np.ndarray:
    """Resolve a scene's joint-indexed value (number, list, or table by joint name).

    Args:
        robot: The robot whose joint names and sizes apply.
        values: A number (broadcast), a tuple (one per coordinate) or a dict by joint name.
        source: The scene file, for error messages.
        key: The scene key, for error messages.
        space: ``"q"`` (length nq) or ``"v"`` (length nv).
        default: Value of coordinates a table does not name.

    Raises:
        SceneError: Wrong length, unknown joint name, or broadcast onto a non-Euclidean q.
    """
    model = robot.model
    size = model.nq if space == "q" else model.nv
    out = np.array(np.broadcast_to(np.asarray(default, dtype=float), (size,)))
    if isinstance(values, dict):
        names = list(robot.joint_names)
        for name, value in values.items():
            if name not in names:
                shown = ", ".join(names[:6]) + (", ..." if len(names) > 6 else "")
                raise SceneError(
                    source, f"{key}.{name}", f"unknown joint; {robot.name} has {shown}"
                )
            joint = model.joints[model.getJointId(name)]
            start, width = (joint.idx_q, joint.nq) if space == "q" else (joint.idx_v, joint.nv)
            if width != 1:
                raise SceneError(
                    source, f"{key}.{name}", f"joint has {width} coordinates; give a list instead"
                )
            out[start] = value
        return out
    if isinstance(values, (tuple, list)):
        if len(values) != size:
            raise SceneError(
                source,
                key,
                f"must have {size} values ({space}-coordinates of {robot.name}), got {len(values)}",
            )
        return np.array(values, dtype=float)
    if space == "q" and model.nq != model.nv:
        raise SceneError(
            source, key, f"{robot.name} has quaternion coordinates; give a list of {size} values"
        )
    out[:] = float(values)
    return out


class Effect:
    """Base class: one declared effect, built once from the scene, evaluated per RHS call.

    Attributes:
        name: The scene name of the effect (registry key).
        uses_velocity: Whether τ depends on v (so it is evaluated only when declared).
        conservative: Whether the effect derives from a potential (energy is then checked).
        adds_torque: Whether :meth:`tau` contributes a generalized force.
    """

    name: ClassVar[str]
    uses_velocity: ClassVar[bool] = False
    conservative: ClassVar[bool] = False
    adds_torque: ClassVar[bool] = True

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        self.robot = robot

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Generalized force of this effect at time t (s), length nv."""
        raise NotImplementedError

    def potential_energy(self, q: np.ndarray) -> float:
        """Potential energy (J) of a conservative effect; 0 for the others."""
        return 0.0


class Gravity(Effect):
    """Uniform gravity ``vector`` (m/s²); the backend forms g(q) in its own recursion."""

    name = "gravity"
    conservative = True
    adds_torque = False

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.vector = np.array(params["vector"], dtype=float)


class Damping(Effect):
    """Viscous joint damping ``τ = -c ⊙ v`` (c in N·m·s/rad or N·s/m)."""

    name = "damping"
    uses_velocity = True

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.c = joint_vector(
            robot, params["coefficient"], source=source, key="effects.damping.coefficient"
        )

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return -self.c * v


def _euclidean(robot: Robot, source: str, key: str) -> None:
    if robot.nq != robot.nv:
        raise SceneError(source, key, f"needs nq = nv; {robot.name} has quaternion coordinates")


class Spring(Effect):
    """Joint springs ``τ = -k ⊙ (q - q_rest)``, energy ``½ Σ k (q - q_rest)²``."""

    name = "spring"
    conservative = True

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        _euclidean(robot, source, "effects.spring")
        key = "effects.spring."
        self.k = joint_vector(robot, params["stiffness"], source=source, key=key + "stiffness")
        self.rest = joint_vector(robot, params["rest"], source=source, key=key + "rest", space="q")

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return -self.k * (q - self.rest)

    def potential_energy(self, q: np.ndarray) -> float:
        return float(0.5 * np.sum(self.k * (q - self.rest) ** 2))


class Torque(Effect):
    """Applied joint torques by law: constant, sinusoid or PD tracking a target."""

    name = "torque"

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.law = params["law"]
        key = "effects.torque."

        def vec(name: str, space: str = "v", default: float = 0.0) -> np.ndarray:
            if name not in params:
                return np.full(robot.nv if space == "v" else robot.nq, default)
            return joint_vector(robot, params[name], source=source, key=key + name, space=space)

        self.value = vec("value")
        if self.law == "sinusoid":
            self.amplitude = vec("amplitude")
            self.omega = 2.0 * np.pi * params["frequency_hz"]
            self.phase = params.get("phase_rad", 0.0)
        elif self.law == "pd":
            _euclidean(robot, source, "effects.torque")
            self.kp, self.kd, self.target = vec("kp"), vec("kd"), vec("target", "q")
        # Only the PD law reads v: declared velocity dependence, per instance.
        self.uses_velocity = self.law == "pd"

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        if self.law == "constant":
            return self.value
        if self.law == "sinusoid":
            return self.value + self.amplitude * np.sin(self.omega * t + self.phase)
        return self.kp * (self.target - q) - self.kd * v


class Wrench(Effect):
    """A constant wrench on a named link: ``τ = J(q)ᵀ [f; n]`` (N, N·m).

    ``frame = "world"``: force and torque in world axes, applied at the link frame's origin
    (Pinocchio ``LOCAL_WORLD_ALIGNED``); ``"local"``: in the link's own axes (``LOCAL``).
    """

    name = "wrench"

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        model = robot.model
        link = params["link"]
        if not model.existFrame(link, pin.FrameType.BODY):
            bodies = [f.name for f in model.frames if f.type == pin.FrameType.BODY]
            shown = ", ".join(bodies[:6]) + (", ..." if len(bodies) > 6 else "")
            raise SceneError(source, "effects.wrench.link", f"unknown link {link!r}; {shown}")
        self.frame_id = model.getFrameId(link, pin.FrameType.BODY)
        self.wrench = pin.Force(np.array(params["force"]), np.array(params["torque"])).vector
        self.reference = (
            pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
            if params["frame"] == "world"
            else pin.ReferenceFrame.LOCAL
        )
        self.data = robot.new_data()

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        J = pin.computeFrameJacobian(self.robot.model, self.data, q, self.frame_id, self.reference)
        return J.T @ self.wrench


#: The registry: scene effect name -> class.
EFFECTS: dict[str, type[Effect]] = {
    cls.name: cls for cls in (Gravity, Damping, Spring, Torque, Wrench)
}


def build_effects(robot: Robot, specs, *, source: str) -> list[Effect]:
    """Instantiate exactly the declared effects from the registry, in declaration order."""
    return [EFFECTS[spec.name](robot, spec.params, source=source) for spec in specs]
