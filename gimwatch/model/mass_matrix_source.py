"""Where M(q) comes from: the declared `MassMatrixSource` every GIM consumer takes.

A source gives ``nv``, ``dof_names``, ``gim(q)`` (M) and ``gim_diagonal(q)`` (diag M), and
declares the faster paths it has, each with a default meaning "not offered", so that
`GimState` (the metric registry) and the watch dispatch to what a source
declares instead of probing it attribute by attribute:

* ``gim_into(q, out)`` — M written into a buffer the caller keeps (MuJoCo's ``mj_fullM``);
  only what the caller reads is guaranteed (Pinocchio's CRBA fills the upper triangle);
* ``diagonal_ratio(q)`` — δ = max M_ii / min M_ii in one call (DeNOC's compiled model), or
  None;
* ``linear_state(q)`` and ``to_public(x)`` — the O(n) state of M at q: ``diagonal()``,
  ``pivots()`` (UDUᵀ), ``matvec(x)`` and ``solve(y)`` in the source's own coordinate order,
  mapped to the public order by ``to_public``; M itself is then never formed;
* ``lean_model()`` — DeNOC's compiled model of the robot (O(n) M·x, M⁻¹·y), or None;
* ``robot`` and ``pinocchio_data()`` — the gimwatch robot whose RNEA/ABA the operator metrics
  (``kappa_tracked``, ``kappa_lanczos``, ...) run, and a Pinocchio Data to reuse;
* ``reads_state`` — M is read from state the source holds, so ``q`` may be None;
* ``check_q`` — whether the watch checks each q against ``robot`` (a simulation's backend
  gets q from its own integrator);
* ``definiteness`` — whether M is positive definite by construction (`GUARANTEED`), checked
  once (`CHECK_ONCE`) or at every sample (`CHECK_EVERY_SAMPLE`) when no metric forms M.

This module imports no Pinocchio: it sits low in the house, under every implementation
(Pinocchio's CRBA, DeNOC, MuJoCo, a matrix in hand).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

import numpy as np

if TYPE_CHECKING:
    from gimwatch.model.robots import Robot

__all__ = [
    "CHECK_EVERY_SAMPLE",
    "CHECK_ONCE",
    "GUARANTEED",
    "Configuration",
    "LinearState",
    "MassMatrixSource",
]

#: M is positive definite by construction: never checked.
GUARANTEED = "guaranteed"
#: M is checked positive definite once, at the first sample (the same code gives the same kind).
CHECK_ONCE = "check_once"
#: M may lose definiteness between samples (MuJoCo's negative ``dof_armature``): every sample.
CHECK_EVERY_SAMPLE = "check_every_sample"
#: A configuration in the source's own layout (a robot's q, MuJoCo's qpos), or None when the
#: source reads the M it holds.
Configuration = Any


class LinearState(Protocol):
    """M at one configuration held in O(n) memory (DeNOC's articulated-body factor)."""

    def diagonal(self) -> np.ndarray:
        """Diag M in the state's own coordinate order."""
        ...

    def pivots(self) -> np.ndarray:
        """Pivots of M = U D Uᵀ (elimination from the tips), in the state's order."""
        ...

    def matvec(self, x: np.ndarray) -> np.ndarray:
        """M·x."""
        ...

    def solve(self, y: np.ndarray) -> np.ndarray:
        """M⁻¹·y."""
        ...


class MassMatrixSource(ABC):
    """Where M(q) comes from: ``nv``, ``dof_names``, ``gim(q)`` and the declared faster paths.

    An abstract base class rather than a `typing.Protocol`: every optional path has a
    default that says "not offered" (None, or the slow path through ``gim``), which a
    Protocol cannot give a class that does not inherit from it. A user's source subclasses
    this, sets ``nv`` and ``dof_names`` and writes ``gim``; the watch checks it once with
    ``isinstance`` and never probes it again. Override a method only to offer a faster path.
    """

    nv: int
    dof_names: tuple[str, ...]
    #: ``gim(None)`` reads the M the source holds (a MuJoCo ``MjData``): q may be omitted.
    reads_state: ClassVar[bool] = False
    #: Whether the watch checks each q against `robot` (False: q comes from a simulation).
    check_q: ClassVar[bool] = True
    #: Whether a watch that never forms M checks it positive definite, and how often.
    definiteness: str = CHECK_ONCE
    #: The robot whose RNEA/ABA operator metrics run, and whose q the watch checks.
    robot: Robot | None = None

    @abstractmethod
    def gim(self, q: Configuration) -> np.ndarray:
        """M(q), shape (nv, nv), symmetric."""

    def gim_into(self, q: Configuration, out: np.ndarray) -> np.ndarray:
        """M(q) for the watch's compiled path, written into ``out`` when the source can."""
        return self.gim(q)

    def gim_diagonal(self, q: Configuration) -> np.ndarray:
        """Diag M(q), length nv (default: read off ``gim(q)``; override to skip forming M)."""
        return np.diag(self.gim(q)).copy()

    def diagonal_ratio(self, q: Configuration) -> float | None:
        """δ = max M_ii / min M_ii in one call (NaN when diag M is bad), or None: not offered."""
        return None

    def linear_state(self, q: Configuration) -> LinearState | None:
        """The O(n) state of M at q (M never formed), or None: not offered."""
        return None

    def to_public(self, x: np.ndarray) -> np.ndarray:
        """A vector of `linear_state`'s order in the public (``dof_names``) order."""
        return x

    def lean_model(self) -> Any:
        """DeNOC's compiled model of `robot` (O(n) M·x, M⁻¹·y, diag M), or None."""
        return None

    def pinocchio_data(self) -> Any:
        """A Pinocchio Data of `robot` to reuse (None: whoever needs one makes it)."""
        return None
