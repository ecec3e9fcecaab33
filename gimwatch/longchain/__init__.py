"""O(n)-time, O(n)-memory dynamics of long chains and trees, without Pinocchio's Data.

Pinocchio's ``Data`` for an n-joint model allocates memory growing as n³ (about 1.8 GB at
n = 300), and the dense GIM itself is n². This subpackage keeps only per-body arrays and
runs the DeNOC recursions (Saha; Shah & Saha 2013, Eqs. 11–13) compiled with numba:

* :mod:`~gimwatch.longchain.bodies` — :class:`Bodies`, the per-body parameters (parent,
  joint type and axis, joint placement, mass, centre of mass, inertia) of a tree of 1-DoF
  joints, built from a :class:`~gimwatch.chains.ChainSpec` without any URDF text;
* :mod:`~gimwatch.longchain.kernels` — the recursions: kinematics, composite mass matrices
  and diag M, M·x (inverse dynamics at rest, no gravity), M⁻¹·x and its pivots (the
  articulated-body / UDUᵀ recursion from the tips), full inverse and forward dynamics;
* :mod:`~gimwatch.longchain.model` — :class:`LinearTimeModel`, the Python face of them,
  and the matrix-free condition number (Lanczos on M and on M⁻¹).

Like :mod:`gimwatch.denoc`, it never imports Pinocchio: it is checked against it.
"""

from gimwatch.longchain.bodies import Bodies, bodies_from_chain
from gimwatch.longchain.model import (
    ConfigurationState,
    LinearTimeModel,
    MatrixFreeKappa,
    matrix_free_kappa,
)

__all__ = [
    "Bodies",
    "ConfigurationState",
    "LinearTimeModel",
    "MatrixFreeKappa",
    "bodies_from_chain",
    "matrix_free_kappa",
]
