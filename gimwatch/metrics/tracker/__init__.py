"""The κ tracker: κ₂ of M(q) along a trajectory at O(n) per sample, exact or saying so.

One public entry: [`KappaTracker`][gimwatch.metrics.tracker.KappaTracker] (and
[`track_kappa`][gimwatch.metrics.tracker.track_kappa] for a whole path), with its record
[`TrackedKappa`][gimwatch.metrics.tracker.TrackedKappa]. Inside the family: `core` (the
method, its fallbacks and stopping rule), `denoc` (its compiled path on DeNOC's model,
shift-invert and the λmin certificate), `krylov` (the thick-restart Lanczos engine) and
`providers` (where the operators M·x and M⁻¹·y come from).
"""

from gimwatch.metrics.tracker.core import KappaTracker, TrackedKappa, track_kappa
from gimwatch.metrics.tracker.providers import PinocchioProducts, gim_products, lean_model

__all__ = [
    "KappaTracker",
    "PinocchioProducts",
    "TrackedKappa",
    "gim_products",
    "lean_model",
    "track_kappa",
]
