"""Conditioning of long chains by the O(n) DeNOC path: no Pinocchio Data, no dense M.

Pinocchio's Data for an n-joint model needs memory growing as n³ (about 1.8 GB at n = 300,
8 GB at 500), and the dense GIM n². Above `DATA_NV_LIMIT` joints
(or on request) gimwatch analyses chains and trees — fixed or floating, with ball and free
joints on any body and several trees — with the compiled DeNOC recursions instead: diag M and
δ in O(n); κ₂ from one cold sample of the κ tracker (its Lanczos on M·x and shift-invert
(M − σ·1)⁻¹·x, O(n) each, both ends certified by Sylvester's law of inertia), κ_S from the same
engine on D^-1/2 M D^-1/2 x and its inverse (the same products, scaled by the O(n) diagonal);
the backward (UDUᵀ) pivots from the articulated-body factor. The forward (LDLᵀ) pivots and
the full spectrum need M itself and are not computed on this path.
"""

from __future__ import annotations

from collections.abc import Collection

import numpy as np
import numpy.typing as npt

from gimwatch.denoc import DenocModel
from gimwatch.errors import InputError
from gimwatch.metrics.dense_analysis import GimAnalysis, analysis_record, check_massless
from gimwatch.metrics.mass_matrix_sources import DenocLinear
from gimwatch.metrics.registry import GimState
from gimwatch.model.chains import ChainSpec
from gimwatch.model.sampling import uniform_in_limits
from gimwatch.suggest import did_you_mean

__all__ = ["LINEAR_METRICS", "analyze_linear", "chain_configurations"]

#: What the O(n) path can compute.
LINEAR_METRICS = ("kappa", "diagonal_ratio", "pivot_ratio_backward", "kappa_equilibrated")


def chain_configurations(spec: ChainSpec, count: int, *, seed: int | None) -> np.ndarray:
    """Random configurations of a generated chain, shape ``(count, n)``, within its limits.

    The chain's limits (`ChainSpec.position_limits`, those its URDF writes) drawn by
    `gimwatch.model.sampling.uniform_in_limits`, as
    [`random_configurations`][gimwatch.model.sampling.random_configurations] draws them for the
    same chain and seed, without building a Pinocchio model.
    """
    if isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1:
        raise InputError("count", "a positive integer", count)
    lower, upper = spec.position_limits()
    return uniform_in_limits(lower, upper, count, seed)


def analyze_linear(
    model: DenocModel,
    q: npt.ArrayLike,
    *,
    name: str,
    metrics: Collection[str] = LINEAR_METRICS,
    seed: int = 0,
    rtol: float = 1e-9,
) -> GimAnalysis:
    """Conditioning of M(q) with O(n) time and memory (any tree DeNOC reads).

    Args:
        model: The DeNOC model: fixed or floating base, free joints, several trees.
        q: Configuration in the model's layout.
        name: Robot name for the record.
        metrics: Which of `LINEAR_METRICS` to compute; the others are None.
        seed: Seed of the Lanczos probe vectors.
        rtol: Relative tolerance on each extreme eigenvalue of M and of S (certified for M).
    """
    unknown = sorted(set(metrics) - set(LINEAR_METRICS))
    if unknown:
        raise InputError(
            "metrics",
            f"among {LINEAR_METRICS} on the O(n) path",
            unknown,
            hint=did_you_mean(unknown[0], LINEAR_METRICS).removeprefix("; "),
        )
    state = GimState(DenocLinear(model), np.asarray(q, dtype=float), lanczos=(seed, rtol))
    check_massless(state.diag, model.dof_names, name=name, source=model.tree.source)
    asked = [key for key in LINEAR_METRICS if key in metrics or key == "diagonal_ratio"]
    return analysis_record(
        state,
        asked,
        name=name,
        nv=model.nv,
        q=q,
        dof_names=model.dof_names,
        method="denoc-linear",
    )
