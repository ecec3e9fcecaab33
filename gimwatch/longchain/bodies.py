"""Per-body parameters of a tree of 1-DoF joints, as flat NumPy arrays.

Body k hangs from joint k; its frame is the joint frame. Bodies are in topological order
(every parent index is smaller than its child's), so one forward sweep and one backward
sweep visit parents before children and children before parents.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from gimwatch.chains import ChainSpec
from gimwatch.errors import InputError

__all__ = ["PRISMATIC", "REVOLUTE", "Bodies", "bodies_from_chain"]

REVOLUTE, PRISMATIC = 0, 1
_AXIS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


@dataclass(frozen=True, eq=False)
class Bodies:
    """A tree of n bodies, each moved by one revolute or prismatic joint.

    Attributes:
        parent: (n,) parent body index, -1 for bodies attached to the fixed base.
        joint_type: (n,) ``REVOLUTE`` (0) or ``PRISMATIC`` (1).
        axis: (n, 3) unit joint axis in the joint frame.
        origin_rotation: (n, 3, 3) joint frame orientation in the parent frame at q = 0.
        origin_position_m: (n, 3) joint frame origin in the parent frame.
        mass_kg: (n,) body masses.
        com_m: (n, 3) centre of mass in the body (joint) frame.
        inertia_kgm2: (n, 3, 3) inertia about the centre of mass, body axes.
        names: joint names, in body order.
    """

    parent: np.ndarray
    joint_type: np.ndarray
    axis: np.ndarray
    origin_rotation: np.ndarray
    origin_position_m: np.ndarray
    mass_kg: np.ndarray
    com_m: np.ndarray
    inertia_kgm2: np.ndarray
    names: tuple[str, ...]

    def __post_init__(self) -> None:
        n = self.parent.shape[0]
        if n < 1 or np.any(self.parent >= np.arange(n)) or np.any(self.parent < -1):
            raise InputError("parent", "a topological order (each parent before its child)",
                             "a body listed before its parent")

    @property
    def n(self) -> int:
        """Number of bodies (and degrees of freedom)."""
        return int(self.parent.shape[0])

    @property
    def nbytes(self) -> int:
        """Memory held by the arrays, in bytes (O(n))."""
        return sum(
            getattr(self, f).nbytes
            for f in ("parent", "joint_type", "axis", "origin_rotation", "origin_position_m",
                      "mass_kg", "com_m", "inertia_kgm2")
        )


def bodies_from_chain(spec: ChainSpec) -> Bodies:
    """The bodies of a generated rod chain, straight from its spec (no URDF text).

    Same geometry as :func:`gimwatch.chains.generate_chain_urdf`: link i starts at joint i,
    points along its local x axis, and joint i+1 sits at its tip.
    """
    n = spec.n
    m = np.asarray(spec.masses_kg)
    length = np.asarray(spec.lengths_m)
    r = np.asarray(spec.radii_m)
    origin = np.zeros((n, 3))
    origin[1:, 0] = length[:-1]
    com = np.zeros((n, 3))
    com[:, 0] = length / 2
    inertia = np.zeros((n, 3, 3))
    inertia[:, 0, 0] = m * r**2 / 2
    inertia[:, 1, 1] = inertia[:, 2, 2] = m * (3 * r**2 + length**2) / 12
    width = len(str(n))
    return Bodies(
        parent=np.arange(-1, n - 1, dtype=np.int64),
        joint_type=np.array([PRISMATIC if k == "prismatic" else REVOLUTE
                             for k in spec.joint_types], dtype=np.int64),
        axis=np.array([_AXIS[a] for a in spec.axes], dtype=float),
        origin_rotation=np.broadcast_to(np.eye(3), (n, 3, 3)).copy(),
        origin_position_m=origin,
        mass_kg=m.astype(float),
        com_m=com,
        inertia_kgm2=inertia,
        names=tuple(f"joint_{i + 1:0{width}d}" for i in range(n)),
    )
