"""The effects a scene may declare, one small class each, in a registry keyed by scene name.

Every effect but gravity contributes a generalized force τ_e(t, q, v) (length nv) to the
equation of motion ``M(q) a + C(q, v) v + g(q) = Σ τ_e``. Gravity instead sets the gravity
vector the dynamics backend uses, so an undeclared gravity is a zero vector and no
gravity term is ever formed. Effects that are not declared are not instantiated at all.

* ``gravity`` — ``g(q)`` through the backend (Pinocchio's ``model.gravity``).
* ``damping`` — viscous joint damping ``τ = -c ⊙ v``.
* ``spring`` — joint springs ``τ = -k ⊙ (q - q_rest)``, potential ``½ Σ k (q - q_rest)²``.
* ``torque`` — applied joint torques by a named law
  ([`gimwatch.simulation.torque_laws`][gimwatch.simulation.torque_laws]).
* ``wrench`` — a constant wrench (force, torque) on a named link, mapped to joint space
  as ``τ = Jᵀ w`` with Pinocchio's frame Jacobian (``LOCAL`` or ``LOCAL_WORLD_ALIGNED``).

How to add an effect: subclass [`Effect`][gimwatch.simulation.effects.Effect], set ``name``,
``parameters`` and the flags, resolve the parameters in ``__init__`` and implement
[`Effect.tau`][gimwatch.simulation.effects.Effect.tau] (and
[`Effect.potential_energy`][gimwatch.simulation.effects.Effect.potential_energy] when
``conservative``); decorate it with [`register`][gimwatch.simulation.effects.register]. The scene
reader validates its table from ``parameters``; the scene reference lists it.
"""

from __future__ import annotations

from typing import Any, ClassVar

import numpy as np
import pinocchio as pin

from gimwatch.errors import SceneError
from gimwatch.model.configuration import coordinate_kinds
from gimwatch.model.robots import Robot
from gimwatch.registries import Registry
from gimwatch.simulation.joint_values import joint_vector
from gimwatch.simulation.parameters import Parameter
from gimwatch.simulation.torque_laws import TORQUE_LAWS, CallableLaw

__all__ = [
    "EFFECTS",
    "CallableTorque",
    "Effect",
    "Gravity",
    "build_effects",
    "joint_vector",
    "register",
]


class Effect:
    """Base class: one declared effect, built once from the scene, evaluated per RHS call.

    Contract:
        * ``name`` — the scene name (``[effects.<name>]``), unique in `EFFECTS`.
        * ``parameters`` — its keys, validated by the scene reader before the robot is known.
        * ``__init__(robot, params, *, source)`` resolves them against the robot (joint names,
          lengths) and raises [`SceneError`][gimwatch.errors.SceneError] naming ``source`` and key.
        * [`tau`][gimwatch.simulation.effects.Effect.tau] returns the generalized force (length nv)
          at each right-hand-side evaluation — a few NumPy or Pinocchio calls, no Python loop over
          joints.
        * ``conservative`` effects implement
          [`potential_energy`][gimwatch.simulation.effects.Effect.potential_energy] (the energy
          check).

    Attributes:
        name: The scene name of the effect (registry key).
        uses_velocity: Whether τ depends on v (so it is evaluated only when declared).
        conservative: Whether the effect derives from a potential (energy is then checked).
        adds_torque: Whether [`tau`][gimwatch.simulation.effects.Effect.tau] contributes a
            generalized force.
    """

    name: ClassVar[str]
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    uses_velocity: bool = False
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


#: The registry: scene effect name -> class.
EFFECTS: Registry[type[Effect]] = Registry("effect")


register = EFFECTS.register
"""Class decorator: add an effect to `EFFECTS` under its ``name``."""


@register
class Gravity(Effect):
    """Uniform gravity ``vector`` (m/s²); the backend forms g(q) in its own recursion."""

    name = "gravity"
    conservative = True
    adds_torque = False
    parameters = (Parameter("vector", "vector3", required=True, doc="g (m/s²), world axes"),)

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.vector = np.array(params["vector"], dtype=float)


@register
class Damping(Effect):
    """Viscous joint damping ``τ = -c ⊙ v`` (c in N·m·s/rad or N·s/m)."""

    name = "damping"
    uses_velocity = True
    parameters = (
        Parameter("coefficient", "joint", required=True, nonnegative=True, doc="c (N·m·s/rad)"),
    )

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.c = joint_vector(
            robot, params["coefficient"], source=source, key="effects.damping.coefficient"
        )

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return -self.c * v


@register
class Spring(Effect):
    """Joint springs ``τ = -k ⊙ (q - q_rest)``, energy ``½ Σ k (q - q_rest)²`` (nq = nv)."""

    name = "spring"
    conservative = True
    parameters = (
        Parameter("stiffness", "joint", required=True, nonnegative=True, doc="k (N·m/rad)"),
        Parameter("rest", "configuration", default=0.0, doc="q_rest (rad or m), default 0"),
    )

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        if robot.nq != robot.nv:
            raise SceneError(
                source,
                "effects.spring",
                f"needs nq = nv; {robot.name} has {coordinate_kinds(robot)}",
            )
        key = "effects.spring."
        self.k = joint_vector(robot, params["stiffness"], source=source, key=key + "stiffness")
        self.rest = joint_vector(robot, params["rest"], source=source, key=key + "rest", space="q")

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return -self.k * (q - self.rest)

    def potential_energy(self, q: np.ndarray) -> float:
        return float(0.5 * np.sum(self.k * (q - self.rest) ** 2))


@register
class Torque(Effect):
    """Applied joint torques by a law of `TORQUE_LAWS`."""

    name = "torque"
    parameters = (
        Parameter("law", "string", required=True, choices=TORQUE_LAWS, doc="the torque law"),
    )

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.law = TORQUE_LAWS[params["law"]](robot, params, source=source)
        self.uses_velocity = self.law.uses_velocity  # declared per instance

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        return self.law(t, q, v)


@register
class Wrench(Effect):
    """A constant wrench on a named link: ``τ = J(q)ᵀ [f; n]`` (N, N·m).

    ``frame = "world"``: force and torque in world axes, applied at the link frame's origin
    (Pinocchio ``LOCAL_WORLD_ALIGNED``); ``"local"``: in the link's own axes (``LOCAL``).
    """

    name = "wrench"
    parameters = (
        Parameter("link", "string", required=True, doc="the link (URDF link name)"),
        Parameter("force", "vector3", default=(0.0, 0.0, 0.0), doc="f (N)"),
        Parameter("torque", "vector3", default=(0.0, 0.0, 0.0), doc="n (N·m)"),
        Parameter(
            "frame", "string", default="world", choices=("world", "local"), doc="axes of f, n"
        ),
    )

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


class CallableTorque(Effect):
    """A Python torque law ``tau(t, q, v)`` handed to ``run_scene`` (not a scene key).

    Its result is checked at every call
    ([`CallableLaw`][gimwatch.simulation.torque_laws.CallableLaw]).
    """

    name = "torque_law"
    uses_velocity = True

    def __init__(self, robot: Robot, law) -> None:
        self.robot = robot
        self.law = CallableLaw(law, robot)

    def tau(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The law's τ(t, q, v), checked."""
        return self.law(t, q, v)


def build_effects(robot: Robot, specs, *, source: str) -> list[Effect]:
    """Instantiate exactly the declared effects from the registry, in declaration order."""
    return [EFFECTS[spec.name](robot, spec.params, source=source) for spec in specs]
