"""DeNOC: an independent GIM and dynamics from the URDF, with numpy and yourdfpy only.

Shah & Saha (2013) write the GIM with the Decoupled Natural Orthogonal Complement (DeNOC)
matrices: twist-propagation matrices A, motion-propagation vectors p and composite mass
matrices M̃ (Eqs. 11–13). This package implements them, Saha's recursive inverse dynamics
and the O(n) UDUᵀ forward dynamics, without Pinocchio, so that the two can check each other
(``gimwatch crosscheck``). It never imports pinocchio.
"""

from gimwatch.denoc.model import DenocModel
from gimwatch.denoc.tree import BodyTree, read_body_tree

__all__ = ["BodyTree", "DenocModel", "read_body_tree"]
