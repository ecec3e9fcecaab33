"""A scene's ``[integrator]`` table: the method, its tolerances or step, and the step budget.

Every run has a step budget, ``[integrator] max_steps`` (default `DEFAULT_MAX_STEPS`,
at most `MAX_FIXED_STEPS`): a scene whose duration needs more fixed steps (``dt``), or
more steps of ``max_step``, than its budget is refused before it runs; an adaptive run that
spends its budget (a stiff spring under RK45) stops with status ``failed`` and the samples
so far. Tolerances are held to a range in which the solution has correct digits.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from gimwatch.errors import SceneError
from gimwatch.simulation.integrators import DEFAULT_MAX_STEPS, INTEGRATORS
from gimwatch.simulation.scene_reader import TableReader

__all__ = [
    "ATOL_MAX",
    "DEFAULT_MAX_STEPS",
    "MAX_DURATION_S",
    "MAX_FIXED_STEPS",
    "RTOL_RANGE",
    "IntegratorSpec",
    "check_steps",
    "read_integrator",
]

#: Fixed integrator steps a scene may ask for at all (its max_steps included).
MAX_FIXED_STEPS = 100_000_000
#: The longest duration simulated (s, 11.6 days): beyond it the smallest step an adaptive
#: method may take (MIN_STEP_FRACTION of the duration) is no longer small.
MAX_DURATION_S = 1e6
#: Tolerances of the adaptive methods: below 1e-14 no step is accurate enough (SciPy raises
#: rtol below 100 eps = 2.2e-14 itself, with a warning; the bench's reference runs at
#: 1e-14), above 0.1 (rtol) or 1 (atol, rad or m) the solution has no correct digit.
RTOL_RANGE = (1e-14, 0.1)
ATOL_MAX = 1.0


@dataclass(frozen=True)
class IntegratorSpec:
    """The integrator: a scipy ``solve_ivp`` method (rtol, atol) or a fixed step (dt, s)."""

    method: str = "DOP853"
    rtol: float = 1e-8
    atol: float = 1e-8
    dt: float | None = None
    max_step: float = math.inf
    max_steps: int = DEFAULT_MAX_STEPS

    @property
    def fixed_step(self) -> bool:
        """Whether the method takes fixed steps of ``dt``."""
        return INTEGRATORS[self.method].fixed_step


def read_integrator(reader: TableReader) -> IntegratorSpec:
    """The validated ``[integrator]`` table."""
    reader.check_keys({"method", "rtol", "atol", "dt", "max_step", "max_steps"})
    method = reader.string("method", "DOP853", choices=tuple(INTEGRATORS))
    max_steps = reader.integer("max_steps", DEFAULT_MAX_STEPS, minimum=1, maximum=MAX_FIXED_STEPS)
    if INTEGRATORS[method].fixed_step:
        if "dt" not in reader.table:
            raise reader.fail("dt", f"is required by the fixed-step method {method}")
        for key in ("rtol", "atol", "max_step"):
            if key in reader.table:
                raise reader.fail(key, f"does not apply to the fixed-step method {method}")
        dt = reader.number("dt", positive=True)
        return IntegratorSpec(method=method, dt=dt, max_steps=max_steps)
    if "dt" in reader.table:
        raise reader.fail("dt", f"applies to fixed-step methods only, not {method}")
    low, high = RTOL_RANGE
    return IntegratorSpec(
        method=method,
        rtol=reader.number("rtol", 1e-8, positive=True, minimum=low, maximum=high),
        atol=reader.number("atol", 1e-8, positive=True, maximum=ATOL_MAX),
        max_step=reader.number("max_step", math.inf, positive=True),
        max_steps=max_steps,
    )


def check_steps(source: str, integrator: IntegratorSpec, duration: float) -> None:
    """The steps a run needs at least (duration / dt, or / max_step) fit in its budget."""
    step, key = (
        (integrator.dt, "integrator.dt")
        if integrator.fixed_step
        else (integrator.max_step, "integrator.max_step")
    )
    if step is None:  # an IntegratorSpec built in Python (a scene's table always has dt)
        raise SceneError(source, key, f"is required by the fixed-step {integrator.method}")
    steps = duration / step
    if integrator.fixed_step and steps > MAX_FIXED_STEPS:
        raise SceneError(
            source, key, f"duration / dt must be at most {MAX_FIXED_STEPS} steps, got {steps:.3g}"
        )
    if steps > integrator.max_steps:
        name = "dt" if integrator.fixed_step else "max_step"
        raise SceneError(
            source,
            key,
            f"duration / {name} = {steps:.3g} steps is more than the step budget of "
            f"{integrator.max_steps} (raise [integrator] max_steps, at most {MAX_FIXED_STEPS})",
        )
