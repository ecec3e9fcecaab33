"""The κ tracker: κ₂ of M(q) along a trajectory at O(n) per sample, exact or saying so.

One public entry: [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] (and
[`track_kappa`][gimwatch.metrics.tracker.track_kappa] for a whole path), with its record
[`TrackedKappa`][gimwatch.metrics.tracker.TrackedKappa]. Inside the family: `core` (the
method, its fallbacks and stopping rule), `denoc` (its compiled path on DeNOC's model,
shift-invert and the λmin certificate), `krylov` (the thick-restart Lanczos engine: the one
Krylov engine of every matrix-free κ in gimwatch), `extremes` (κ at one configuration: one cold,
certified sample) and `providers` (where the operators M·x and M⁻¹·y come from).
"""

from gimwatch.metrics.tracker.core import KappaTracker, TrackedKappa, TrackerSettings, track_kappa
from gimwatch.metrics.tracker.extremes import extreme_eigenvalues
from gimwatch.metrics.tracker.providers import PinocchioProducts, gim_products, lean_model

__all__ = [
    "KappaTracker",
    "PinocchioProducts",
    "TrackedKappa",
    "TrackerSettings",
    "extreme_eigenvalues",
    "gim_products",
    "lean_model",
    "track_kappa",
]
