"""The generalized inertia matrix (GIM) M(q) of a robot, from Pinocchio.

* [`gim`][gimwatch.model.inertia.gim] — the full symmetric M(q) from the composite-rigid-body
  algorithm (CRBA), O(n^2) time and memory.
* [`gim_diagonal`][gimwatch.model.inertia.gim_diagonal] — only diag M(q), in O(n) time without
  forming M, from the composite (subtree) inertias: ``M_kk = S_k^T Ĩ_k S_k`` where S_k is the motion
  subspace of coordinate k and Ĩ_k the composite inertia of the subtree below its joint, both in the
  world frame. This is the diagonal of Shah & Saha (2013), Eq. (11), ``I_ii = p_i^T M̃_i p_i``.
"""

from __future__ import annotations

import threading
import weakref

import numpy as np
import numpy.typing as npt
import pinocchio as pin

from gimwatch.model.q_checks import as_configuration
from gimwatch.model.robots import Robot

__all__ = ["gim", "gim_diagonal"]

# One Pinocchio Data per robot and thread, made on the first call without ``data=``: building
# a Data costs more than the CRBA itself (10x at n = 7, 160x at n = 200).
_cached = threading.local()


def _data_of(robot: Robot) -> pin.Data:
    """The cached Data of ``robot`` for this thread (dropped with the robot)."""
    cache = getattr(_cached, "by_robot", None)
    if cache is None:
        cache = _cached.by_robot = weakref.WeakKeyDictionary()
    data = cache.get(robot)
    if data is None:
        data = cache[robot] = robot.new_data()
    return data


def gim(robot: Robot, q: npt.ArrayLike, *, data: pin.Data | None = None) -> np.ndarray:
    """M(q) from Pinocchio's CRBA, symmetric, shape (nv, nv), in SI units (kg, kg·m, kg·m²).

    Args:
        robot: The robot.
        q: Configuration, length nq.
        data: A Pinocchio Data to use; when omitted, one kept for the robot (per thread) is
            reused, so repeated calls cost what ``pin.crba`` costs.
    """
    q = as_configuration(robot, q)
    data = _data_of(robot) if data is None else data
    return np.array(pin.crba(robot.model, data, q))


def gim_diagonal(robot: Robot, q: npt.ArrayLike, *, data: pin.Data | None = None) -> np.ndarray:
    """Diag M(q) in O(n) time, without forming M.

    Pinocchio's centroidal map pass fills the world-frame motion subspaces J (6 x nv) and
    the centroidal momentum matrix Ag = X_G^* Ĩ J (6 x nv). Moving each force column back
    from the centre of mass G to the world origin (n_O = n_G + c × f) gives Ĩ_k S_k, so
    ``M_kk = S_k · (Ĩ_k S_k)`` is one dot product per column.
    """
    q = as_configuration(robot, q)
    data = _data_of(robot) if data is None else data
    # reshape: eigenpy hands back a 6 x 1 matrix as a vector when nv = 1
    force = np.reshape(pin.computeCentroidalMap(robot.model, data, q), (6, -1)).copy()
    cx, cy, cz = data.com[0]
    skew = np.array([[0.0, -cz, cy], [cz, 0.0, -cx], [-cy, cx, 0.0]])
    force[3:] += skew @ force[:3]  # torque about the origin: n_O = n_G + c x f
    diagonal = np.einsum("ij,ij->j", np.reshape(data.J, (6, -1)), force)
    return diagonal + robot.model.armature  # rotor inertia: on M's diagonal, as in CRBA
