"""DeNOC: an independent GIM and dynamics from the URDF, with numpy, numba and yourdfpy only.

Shah & Saha (2013) write the GIM with the Decoupled Natural Orthogonal Complement (DeNOC)
matrices: twist-propagation matrices A, motion-propagation vectors p and composite mass
matrices M̃ (Eqs. 11–13). This package implements them, Saha's recursive inverse dynamics
and the O(n) UDUᵀ forward dynamics, without Pinocchio, so that the two can check each other
(``gimwatch crosscheck``). It never imports pinocchio.

* [`DenocModel`][gimwatch.denoc.DenocModel] — any URDF tree, fixed or floating base, in Pinocchio's
  coordinate layout; the recursions batched per tree depth in NumPy (`.recursions`). A tree
  made from arrays ([`body_tree`][gimwatch.denoc.body_tree]) may also have ball and free
  joints on any body and several trees (many free bodies, robots side by side); its O(n)
  operators are a [`LeanState`][gimwatch.denoc.LeanState].
* [`LeanModel`][gimwatch.denoc.LeanModel] — the O(n) operations (diag M, M·x, M⁻¹·y, forward and
  inverse dynamics) as one compiled call each with preallocated buffers, fixed and floating bases,
  in Pinocchio's coordinate order (`.fused`); ``DenocModel.lean()`` builds it.
* [`LinearTimeModel`][gimwatch.denoc.LinearTimeModel] — fixed-base trees, one angle per body, on the
  same compiled kernels (`.fused`): O(n) time and memory, for chains of 10^4–10^5 links. Their
  matrix-free condition number is the metrics layer's
  ([`extreme_eigenvalues`][gimwatch.metrics.tracker.extremes.extreme_eigenvalues]).
"""

from gimwatch.denoc.chain import chain_body_tree
from gimwatch.denoc.lean import LeanModel, LeanState
from gimwatch.denoc.linear import ConfigurationState, LinearTimeModel
from gimwatch.denoc.model import DenocModel
from gimwatch.denoc.tree import BodyTree, body_tree, read_body_tree

__all__ = [
    "BodyTree",
    "ConfigurationState",
    "DenocModel",
    "LeanModel",
    "LeanState",
    "LinearTimeModel",
    "body_tree",
    "chain_body_tree",
    "read_body_tree",
]
