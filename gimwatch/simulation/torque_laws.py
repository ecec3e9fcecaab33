"""Torque laws: the generalized force τ(t, q, v) of the ``torque`` effect, in a registry.

A scene declares ``[effects.torque]`` with ``law = "<name>"`` and that law's parameters;
from Python, any callable ``tau(t, q, v)`` can drive a scene
(``run_scene(scene, torque_law=f)``), wrapped in
[`CallableLaw`][gimwatch.simulation.torque_laws.CallableLaw], which checks what it returns.

* ``constant`` — ``τ = τ₀`` (``value``).
* ``sinusoid`` — ``τ = τ₀ + A sin(2π f t + φ)`` (``amplitude``, ``frequency_hz``,
  ``phase_rad``, ``value``).
* ``pd`` — ``τ = k_p ⊙ (q* ⊖ q) − k_d ⊙ v`` (``kp``, ``kd``, ``target``), where ``q* ⊖ q``
  is ``q* − q`` for Euclidean q and Pinocchio's ``difference(q, q*)`` otherwise (a
  continuous joint's angle error wrapped to (−π, π]).

How to add a law: subclass [`TorqueLaw`][gimwatch.simulation.torque_laws.TorqueLaw], set `name` and
`parameters` (validated by the scene reader), compute what does not
change in ``__init__`` and implement ``__call__``; decorate the class with
[`register`][gimwatch.simulation.torque_laws.register]. Nothing else changes: the scene schema, the
CLI and the scene reference read `TORQUE_LAWS`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, ClassVar

import numpy as np
import pinocchio as pin

from gimwatch.errors import GimwatchError
from gimwatch.model.robots import Robot
from gimwatch.registries import Registry
from gimwatch.simulation.joint_values import joint_vector
from gimwatch.simulation.parameters import Parameter

__all__ = ["TORQUE_LAWS", "CallableLaw", "TorqueLaw", "TorqueLawError", "register"]


class TorqueLawError(GimwatchError, ValueError):
    """A torque law returned something that is not a generalized force, or raised."""

    def __init__(self, law: str, problem: str) -> None:
        self.law, self.problem = law, problem
        super().__init__(f"torque law {law}: {problem}")


class TorqueLaw:
    """Base class of the torque laws: τ(t, q, v), length nv (N·m or N).

    Contract:
        * ``name`` — the scene name (``law = "name"``), unique in `TORQUE_LAWS`.
        * ``parameters`` — the law's keys (`Parameter`);
          the scene reader refuses others and requires the ``required`` ones.
        * ``uses_velocity`` — whether τ reads v.
        * ``__init__(robot, params, *, source)`` resolves joint-indexed values against the
          robot once (``joint_vector``), raising [`SceneError`][gimwatch.errors.SceneError] that
          names ``source`` and the key.
        * ``__call__(t, q, v)`` is called at every right-hand-side evaluation: keep it to a few
          NumPy operations; it may return a read-only array.
    """

    name: ClassVar[str]
    parameters: ClassVar[tuple[Parameter, ...]] = ()
    uses_velocity: ClassVar[bool] = False

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        self.robot = robot
        self._params, self._source = params, source

    def vector(self, name: str, space: str = "v") -> np.ndarray:
        """The joint-indexed parameter ``name`` (zeros when absent)."""
        robot = self.robot
        if name not in self._params:
            return np.full(robot.nv if space == "v" else robot.nq, 0.0)
        key = f"effects.torque.{name}"
        return joint_vector(robot, self._params[name], source=self._source, key=key, space=space)

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """Generalized force at time t (s), length nv."""
        raise NotImplementedError


#: The registry: scene law name -> class.
TORQUE_LAWS: Registry[type[TorqueLaw]] = Registry("torque law")


register = TORQUE_LAWS.register
"""Class decorator: add a torque law to `TORQUE_LAWS` under its ``name``."""


_VALUE = Parameter("value", "joint", doc="constant torque τ₀ (N·m or N), default 0")


@register
class Constant(TorqueLaw):
    """``τ = τ₀``."""

    name = "constant"
    parameters = (Parameter("value", "joint", required=True, doc="τ₀ (N·m or N)"),)

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.value = self.vector("value")

    def __call__(self, t, q, v):
        return self.value


@register
class Sinusoid(TorqueLaw):
    """``τ = τ₀ + A sin(2π f t + φ)``."""

    name = "sinusoid"
    parameters = (
        Parameter("amplitude", "joint", required=True, doc="A (N·m or N)"),
        Parameter("frequency_hz", "number", required=True, positive=True, doc="f (Hz)"),
        Parameter("phase_rad", "number", doc="φ (rad), default 0"),
        _VALUE,
    )

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.value = self.vector("value")
        self.amplitude = self.vector("amplitude")
        self.omega = 2.0 * np.pi * params["frequency_hz"]
        self.phase = params.get("phase_rad", 0.0)

    def __call__(self, t, q, v):
        return self.value + self.amplitude * np.sin(self.omega * t + self.phase)


@register
class PD(TorqueLaw):
    """``τ = k_p ⊙ (q* ⊖ q) − k_d ⊙ v`` tracking a fixed target configuration q*."""

    name = "pd"
    uses_velocity = True
    parameters = (
        Parameter("kp", "joint", required=True, nonnegative=True, doc="k_p (N·m/rad or N/m)"),
        Parameter("kd", "joint", required=True, nonnegative=True, doc="k_d (N·m·s/rad or N·s/m)"),
        Parameter("target", "configuration", required=True, doc="q* (rad or m; angles)"),
    )

    def __init__(self, robot: Robot, params: dict[str, Any], *, source: str) -> None:
        super().__init__(robot, params, source=source)
        self.kp, self.kd = self.vector("kp"), self.vector("kd")
        self.target = self.vector("target", "q")
        self.euclidean = robot.nq == robot.nv

    def __call__(self, t, q, v):
        if self.euclidean:
            return self.kp * (self.target - q) - self.kd * v
        error = pin.difference(self.robot.model, q, self.target)
        return self.kp * error - self.kd * v


class CallableLaw:
    """A Python callable ``tau(t, q, v)`` used as a torque law; its output is checked.

    Every call's result must be a real, finite array of shape (nv,); anything else (and an
    exception inside the law) is a
    [`TorqueLawError`][gimwatch.simulation.torque_laws.TorqueLawError] naming the law.
    """

    uses_velocity = True

    def __init__(self, law: Callable[[float, np.ndarray, np.ndarray], Any], robot: Robot) -> None:
        if not callable(law):
            raise TorqueLawError(repr(law), "must be a callable tau(t, q, v)")
        self.law, self.nv = law, robot.nv
        self.name = getattr(law, "__qualname__", None) or repr(law)
        self.robot_name = robot.name

    def __call__(self, t: float, q: np.ndarray, v: np.ndarray) -> np.ndarray:
        """The law's τ(t, q, v) as a float array, or `TorqueLawError`.

        The law sees read-only views of q and v (no copy): writing to them would change the
        integrator's state behind its back, so it is an error naming the law.
        """
        q_view, v_view = q.view(), v.view()
        q_view.flags.writeable = v_view.flags.writeable = False
        try:
            tau = self.law(t, q_view, v_view)
        except GimwatchError:
            raise
        except ValueError as exc:
            if "read-only" not in str(exc):
                raise TorqueLawError(
                    self.name, f"raised ValueError at t = {t:.6g} s: {exc}"
                ) from exc
            raise TorqueLawError(
                self.name,
                f"must not modify q or v (read-only; copy them first) at t = {t:.6g} s: {exc}",
            ) from exc
        except Exception as exc:
            raise TorqueLawError(
                self.name, f"raised {exc.__class__.__name__} at t = {t:.6g} s: {exc}"
            ) from exc
        array = np.asarray(tau)
        if array.shape != (self.nv,):
            raise TorqueLawError(
                self.name,
                f"must return shape ({self.nv},) (nv of {self.robot_name}), got {array.shape} "
                f"at t = {t:.6g} s",
            )
        if np.iscomplexobj(array) or not np.issubdtype(array.dtype, np.number):
            raise TorqueLawError(
                self.name, f"must return real numbers, got dtype {array.dtype} at t = {t:.6g} s"
            )
        array = np.array(array, dtype=float)  # a copy: τ may be q or v itself
        if not np.all(np.isfinite(array)):
            raise TorqueLawError(
                self.name, f"must return finite values, got {array.tolist()!r} at t = {t:.6g} s"
            )
        return array
