"""Local coordinates on the configuration manifold: q = integrate(q_anchor, Δq).

A robot with continuous joints ((cos θ, sin θ), nq = 2, nv = 1), a floating base
(position + unit quaternion) or spherical joints has nq > nv: its q lives on a manifold, not
in R^nq, so an integrator may not add increments to q. The integrators instead carry the
state (Δq ∈ R^nv, v) around an anchor configuration q_anchor, with

    q = integrate(q_anchor, Δq)            (Pinocchio's exponential map, ``pin.integrate``)
    dΔq/dt = J(Δq)⁻¹ v                     J = ∂ integrate(q_anchor, Δq) / ∂Δq

(``pin.dIntegrate`` with respect to its second argument; J is the identity for joints whose
group is commutative — revolute, prismatic, continuous — so there the equation is
``dΔq/dt = v`` and no matrix is formed). The anchor is moved to the current configuration
between samples or steps (re-anchoring), so Δq stays small and J well conditioned.

For nq = nv (every joint revolute or prismatic) the chart is the identity, q itself is the
state, and nothing of this module costs anything.
"""

from __future__ import annotations

import numpy as np
import pinocchio as pin

__all__ = ["LocalChart"]


class LocalChart:
    """The map between (q_anchor, Δq) and q for one Pinocchio model.

    Attributes:
        euclidean: nq = nv: q is a vector and Δq = q − q_anchor.
        commutative: Every joint's group is commutative (J = I): no solve per evaluation.
    """

    def __init__(self, model: pin.Model) -> None:
        self.model = model
        self.euclidean = model.nq == model.nv
        self.commutative = all(j.nq == j.nv or j.nv == 1 for j in model.joints[1:])

    def integrate(self, q: np.ndarray, dq: np.ndarray) -> np.ndarray:
        """Return q ⊕ Δq: ``q + Δq`` for Euclidean q, else Pinocchio's ``integrate``."""
        return q + dq if self.euclidean else pin.integrate(self.model, q, dq)

    def local_rate(self, anchor: np.ndarray, dq: np.ndarray, v: np.ndarray) -> np.ndarray:
        """dΔq/dt = J(Δq)⁻¹ v at q = anchor ⊕ Δq (v itself when J = I)."""
        if self.commutative:
            return v
        J = pin.dIntegrate(self.model, anchor, dq, pin.ArgumentPosition.ARG1)
        return np.linalg.solve(J, v)
