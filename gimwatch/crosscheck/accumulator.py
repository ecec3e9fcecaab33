"""The cross-check's accumulator: the worst errors over the samples, the notes, the verdict.

Subjects report each error under a key (``gim``, ``diag``, ``tau``, ``qdd``, ``backward``,
``pivots``, ``mujoco``) and each per-sample bound (q̈ and pivots within max(tolerance, κ·ε));
the reference reports M at each sample. `ErrorAccumulator.result` turns them into one
`CrossCheckResult`: keys no subject compared are None, q̈ is None once M was singular, and a
run where M ≡ 0 at every sample is "not compared", never a pass.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from gimwatch.crosscheck.reference import EPS, PinocchioReference, ReferenceSample

__all__ = ["ERROR_KEYS", "CrossCheckResult", "ErrorAccumulator"]

#: The errors a cross-check keeps (the worst over the samples), by key.
ERROR_KEYS = ("gim", "diag", "tau", "qdd", "backward", "pivots", "mujoco")

#: The errors held to the tolerance itself (q̈'s forward error and the pivots are held to
#: max(tolerance, κ·ε) sample by sample instead).
_HELD_TO_TOLERANCE = ("gim", "diag", "tau", "backward", "mujoco")


@dataclass(frozen=True)
class CrossCheckResult:
    """Worst relative errors of DeNOC against Pinocchio over the samples of one robot.

    Attributes:
        robot: Robot name.
        floating: Whether the base was a free-flyer.
        nv: Number of velocity coordinates.
        samples: Number of random states.
        gim_rel_err: Worst ‖M − M_crba‖ / ‖M_crba‖ (Frobenius).
        gim_diagonal_rel_err: Worst error of DeNOC's O(n) diagonal against diag(M_crba).
        tau_rel_err: Worst error of τ against ``rnea``.
        qdd_rel_err: Worst forward error of q̈ against ``aba``; None when M(q) is singular.
        qdd_backward_err: Worst ‖M_ref (q̈ − q̈_ref)‖ / (‖M_ref‖₂ ‖q̈_ref‖); None when M(q)
            is singular.
        pivots_rel_err: Worst error of the UDUᵀ pivots against ``cholesky.decompose``
            (only those eliminated before a zero one when M is singular; inf if the two
            meet the zero pivot at different coordinates).
        kappa_max: Largest 2-norm condition number of M over the samples (inf if singular).
        tolerance: The tolerance the errors were held to.
        passed: GIM, diagonal, τ and the q̈ backward error within the tolerance; q̈ and
            pivot forward errors within max(tolerance, κ·ε) at every sample.
        note: Why a quantity was not compared, and which limits were placeholders, or "".
        mujoco_gim_rel_err: Worst error of MuJoCo's ``mj_fullM`` (in Pinocchio's
            coordinates) against ``crba``; None without ``peer="mujoco"``.
        placeholder_limits: Joints whose placeholder limits were replaced by ±π rad / ±1 m.
        mujoco_refusal: Why MuJoCo refused the robot (the link and its reason), or "".
        status: ``"passed"``, ``"failed"``, or ``"not compared"`` when there was nothing to
            compare (M ≡ 0: no moving mass) — never counted as a pass; the reason is in
            ``note``.
    """

    robot: str
    floating: bool
    nv: int
    samples: int
    gim_rel_err: float | None
    gim_diagonal_rel_err: float | None
    tau_rel_err: float | None
    qdd_rel_err: float | None
    qdd_backward_err: float | None
    pivots_rel_err: float | None
    kappa_max: float
    tolerance: float
    passed: bool
    note: str = ""
    mujoco_gim_rel_err: float | None = None
    placeholder_limits: tuple[str, ...] = ()
    mujoco_refusal: str = ""
    status: str = ""

    def __post_init__(self) -> None:
        if not self.status:
            object.__setattr__(self, "status", "passed" if self.passed else "failed")

    def to_dict(self) -> dict:
        """The record as a plain dict (for JSON)."""
        return asdict(self)


class ErrorAccumulator:
    """The worst errors and the per-sample verdict of one robot's cross-check.

    Args:
        tolerance: Largest relative error that passes, in (0, 1).
    """

    def __init__(self, tolerance: float) -> None:
        self.tolerance = tolerance
        self.errors: dict[str, float] = dict.fromkeys(ERROR_KEYS, 0.0)
        self.kappa_max = 0.0
        self.within_bounds = True
        self.singular_note = ""
        self.largest_entry = 0.0

    def add(self, key: str, error: float) -> None:
        """Keep the larger error; NaN wins (``max`` would keep 0.0 against NaN)."""
        current = self.errors[key]
        self.errors[key] = error if np.isnan(error) or error > current else current

    def hold(self, within: bool) -> None:
        """A per-sample bound (q̈ or pivots within max(tolerance, κ·ε)) held or broken."""
        self.within_bounds &= within

    def allowed(self, sample: ReferenceSample) -> float:
        """The bound of a forward error at this sample: max(tolerance, κ·ε)."""
        return max(self.tolerance, sample.kappa * EPS)

    def add_reference(self, sample: ReferenceSample, reference: PinocchioReference) -> None:
        """Record M at one sample: κ, its largest entry, and the first singular M's note."""
        self.largest_entry = max(self.largest_entry, float(np.abs(sample.M).max(initial=0.0)))
        self.kappa_max = max(self.kappa_max, sample.kappa)
        if sample.rank_deficient and not self.singular_note:
            lowest, highest = sample.eigenvalues[0], sample.eigenvalues[-1]
            self.singular_note = (
                f"M(q) is singular at a sample (λmin = {lowest:.3g} <= nv·ε·λmax = "
                f"{reference.robot.nv * EPS * highest:.3g}; null direction on "
                f"{reference.singular_joints(sample.M)}): q̈ is undefined and not compared"
            )

    @property
    def vacuous(self) -> bool:
        """M ≡ 0 at every sample: every error is 0 / 1 = 0, nothing was compared."""
        return self.largest_entry == 0.0

    def final_errors(self, compared: set[str]) -> dict[str, float | None]:
        """The worst errors, None for keys no subject compared and for q̈ once M was singular."""
        errors: dict[str, float | None] = {
            key: (value if key in compared else None) for key, value in self.errors.items()
        }
        if self.singular_note and "qdd" in compared:
            errors["qdd"] = errors["backward"] = None
        return errors

    def passed(self, errors: dict[str, float | None]) -> bool:
        """Every bound held, every error within the tolerance, no NaN, something compared."""
        within = all(
            e <= self.tolerance for e in (errors[k] for k in _HELD_TO_TOLERANCE) if e is not None
        )
        nan = any(e is not None and np.isnan(e) for e in (*errors.values(), self.kappa_max))
        return bool(self.within_bounds and within and not nan) and not self.vacuous
