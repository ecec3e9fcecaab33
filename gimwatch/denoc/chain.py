"""The [`BodyTree`][gimwatch.denoc.BodyTree] of a generated rod chain, without URDF text.

Reading a 10^5-link URDF through an XML parser costs more than every recursion on it; the
chain's bodies follow directly from its [`ChainSpec`][gimwatch.model.chains.ChainSpec], with the
same geometry as
[`generate_chain_urdf`][gimwatch.model.chains.generate_chain_urdf] (tests
compare the two).
"""

from __future__ import annotations

import numpy as np

from gimwatch.denoc.tree import JOINT_KINDS, BodyTree
from gimwatch.model.chains import ChainSpec

__all__ = ["chain_body_tree"]

_AXIS = {"x": (1.0, 0.0, 0.0), "y": (0.0, 1.0, 0.0), "z": (0.0, 0.0, 1.0)}


def chain_body_tree(spec: ChainSpec) -> BodyTree:
    """Bodies of the chain: link i starts at joint i, along its x axis; joint i+1 at its tip.

    Body 0 is the fixed, massless ``base_link``; body i (1..n) is ``link_i`` on ``joint_i``.
    """
    n = spec.n
    m = np.asarray(spec.masses_kg)
    length = np.asarray(spec.lengths_m)
    r = np.asarray(spec.radii_m)
    translation = np.zeros((n + 1, 3))
    translation[2:, 0] = length[:-1]
    com = np.zeros((n + 1, 3))
    com[1:, 0] = length / 2
    inertia = np.zeros((n + 1, 3, 3))
    inertia[1:, 0, 0] = m * r**2 / 2
    inertia[1:, 1, 1] = inertia[1:, 2, 2] = m * (3 * r**2 + length**2) / 12
    width = len(str(n))
    return BodyTree(
        source=f"<generated {spec.name}>",
        floating=False,
        joint_names=("", *(f"joint_{i + 1:0{width}d}" for i in range(n))),
        parent=np.arange(-1, n, dtype=np.intp),
        kind=np.array([0, *(JOINT_KINDS[k] for k in spec.joint_types)], dtype=np.intp),
        placement_rotation=np.broadcast_to(np.eye(3), (n + 1, 3, 3)).copy(),
        placement_translation=translation,
        axis=np.array([(0.0, 0.0, 0.0), *(_AXIS[a] for a in spec.axes)]),
        mass=np.concatenate([[0.0], m]),
        com=com,
        inertia=inertia,
        levels=tuple(np.arange(1, n + 1, dtype=np.intp).reshape(n, 1)),
    )
