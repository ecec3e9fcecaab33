"""The stress suite: on each hard case (`gimwatch.stress.cases`), do the numbers stay right?

Per case, at its configuration q with seeded random v ~ U(−1, 1) and τ ~ U(−10, 10):

1. M(q) is symmetric and positive definite (a Cholesky factorisation succeeds);
2. DeNOC's M equals the reference M: Pinocchio's CRBA (relative Frobenius error ≤ 1e-10),
   or the planar closed form in mpmath when Pinocchio's Data would not fit (nv > 400);
3. q̈ from ``aba``, ``crba-cholesky`` and ``denoc`` is within ``C·κ·eps`` of an mpmath
   reference at 50 digits (relative 2-norm error), with `ERROR_CONSTANT` C = 10·√nv;
4. the watch's estimators (κ, δ, αδ, pivot ratios, LAPACK's rcond) are finite;
5. optionally, a 5 s gravity simulation keeps every value finite and the relative energy
   drift below `ENERGY_DRIFT_LIMIT` (1e-8).

Why C = 10·√nv: a backward-stable solve of M a = b has ‖Δa‖/‖a‖ ≤ κ·η/(1 − κη) where the
normwise backward error η of Cholesky (and of the ABA/UDUᵀ recursions) is a modest multiple
of eps that grows with n in the worst case as O(n) and in practice as O(√n) (Higham,
*Accuracy and Stability of Numerical Algorithms*, Sec. 10.1 and 3.1); forming M and the
bias in float64 adds another such term. 10·√nv bounds every case measured with a margin
(the table reports error/(κ·eps) so the margin can be read off).

References: planar revolute chains use the closed-form Lagrangian of
[`gimwatch.stress.reference_planar`][gimwatch.stress.reference_planar] (independent of Pinocchio and
DeNOC, even of the URDF); every
other case uses
[`TreeReference`][gimwatch.stress.reference_tree.TreeReference],
Featherstone's ABA in mpmath on the body tree read by DeNOC's URDF reader (independent of both
codes' recursions and arithmetic, not of that reader).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass

import numpy as np
import scipy.linalg

from gimwatch.errors import InputError
from gimwatch.metrics import conditioning
from gimwatch.metrics.denoc_robot import denoc_model
from gimwatch.metrics.registry import GimState, evaluate
from gimwatch.model.robots import DATA_NV_LIMIT, Robot
from gimwatch.stress.cases import CASES, StressCase
from gimwatch.watch.sources import GivenMatrix

__all__ = [
    "ENERGY_DRIFT_LIMIT",
    "METHODS",
    "StressResult",
    "error_constant",
    "run_case",
    "run_stress",
    "stress_markdown",
]

EPS = float(np.finfo(float).eps)
METHODS = ("aba", "crba-cholesky", "denoc")
GIM_RTOL = 1e-10
#: The planar closed form solves with mpmath LU, O(n³) (~25 s at n = 200); longer planar
#: chains use the O(n) mpmath ABA, which the tests check against the closed form.
PLANAR_REFERENCE_MAX_NV = 100
#: Relative energy drift a 5 s simulation may show: 10× the worst measured (1.2e-9,
#: feather-root-20, DOP853 at 1e-10; RK4 at 1 ms on the floating bases: ≤ 1.5e-13).
ENERGY_DRIFT_LIMIT = 1e-8
SIMULATION_S = 5.0


def error_constant(nv: int) -> float:
    """C of the bound ‖q̈ − q̈_ref‖/‖q̈_ref‖ ≤ C·κ·eps: 10·√nv (see the module docstring)."""
    return 10.0 * math.sqrt(nv)


@dataclass(frozen=True)
class StressResult:
    """What one case showed. Errors are relative 2-norm errors; None = not computed (note).

    Attributes:
        case: Case name.
        family: Case family.
        nv: Velocity coordinates.
        kappa: κ₂(M) from float64 eigenvalues (inaccurate above ~1e15).
        delta: δ = max/min diag M.
        cholesky_ok: A Cholesky factorisation of M succeeded.
        gim_error: DeNOC's M against the reference M (``gim_reference``).
        gim_reference: ``crba`` or ``planar closed form (mpmath)``.
        errors: q̈ error per method of `METHODS` against the mpmath reference.
        bound: C·κ·eps.
        reference: Which mpmath reference.
        estimators_finite: κ, δ, αδ, pivot ratios and rcond all finite.
        sim_status: Status of the 5 s simulation ("" when not run).
        sim_energy_drift: Its relative energy drift (None when not run).
        passed: Every check held.
        note: What was not computed and why, or what failed.
    """

    case: str
    family: str
    nv: int
    kappa: float
    delta: float
    cholesky_ok: bool
    gim_error: float | None
    gim_reference: str
    errors: dict[str, float | None]
    bound: float
    reference: str
    estimators_finite: bool
    sim_status: str
    sim_energy_drift: float | None
    passed: bool
    note: str = ""

    def to_dict(self) -> dict:
        """The record as a plain dict (for JSON)."""
        return asdict(self)


def _planar(case: StressCase):
    """The planar closed-form reference of a planar revolute chain case, else None."""
    from gimwatch.stress.reference_planar import PlanarChainReference

    spec = case.spec
    if spec is None or any(a != "z" for a in spec.axes):
        return None
    if any(k != "revolute" for k in spec.joint_types):
        return None
    return PlanarChainReference(spec, gravity_m_s2=case.gravity_m_s2[:2])


def _reference(case: StressCase, robot: Robot):
    """(name, q̈ function) of the mpmath reference for the case."""
    planar = _planar(case)
    if planar is not None and robot.nv <= PLANAR_REFERENCE_MAX_NV:
        return "planar closed form (mpmath)", planar.forward_dynamics
    from gimwatch.denoc.tree import read_body_tree
    from gimwatch.stress.reference_tree import TreeReference

    model = robot.model
    q_index = {model.names[j]: model.joints[j].idx_q for j in range(1, model.njoints)}
    v_index = {model.names[j]: model.joints[j].idx_v for j in range(1, model.njoints)}
    tree = read_body_tree(robot.urdf_xml, floating=robot.floating, source=robot.source)
    ref = TreeReference(tree, q_index, v_index, gravity=case.gravity_m_s2)
    return "ABA in mpmath", ref.forward_dynamics


def _pinocchio_methods(robot: Robot, gravity) -> tuple[dict[str, Callable], Callable]:
    from gimwatch.simulation.backends import make_backend

    aba = make_backend("aba", robot, np.asarray(gravity))
    crba = make_backend("crba-cholesky", robot, np.asarray(gravity))

    def gim(q):
        import pinocchio as pin

        upper = np.triu(pin.crba(crba.model, crba.data, q))
        return upper + np.triu(upper, 1).T

    methods = {"aba": aba.forward_dynamics, "crba-cholesky": crba.forward_dynamics}
    return methods, gim


#: The registry metrics whose values on a hard case must be finite.
FINITE_METRICS = (
    "kappa",
    "diagonal_ratio",
    "scaled_diagonal_ratio",
    "pivot_ratio_forward",
    "pivot_ratio_backward",
    "rcond",
)


def _estimators_finite(M: np.ndarray) -> bool:
    values = evaluate(FINITE_METRICS, GimState(GivenMatrix(len(M)), full=True, matrix=M))
    return bool(np.all(np.isfinite(list(values.values()))))


def _gim_against_reference(
    case: StressCase,
    q: np.ndarray,
    M_denoc: np.ndarray,
    crba_gim: Callable | None,
    notes: list[str],
) -> tuple[np.ndarray, float | None, str]:
    """M to judge (crba's, else DeNOC's), DeNOC's GIM error, and what it was measured against.

    The error is against crba (``crba_gim``, None beyond Pinocchio's Data), or else against
    the planar closed form (mpmath); None (and "") when there is neither.
    """
    nv = len(M_denoc)
    if crba_gim is not None:
        M = crba_gim(q)
        M_ref: np.ndarray | None = M
        gim_reference = "crba"
    else:
        notes.append(f"nv = {nv} > {DATA_NV_LIMIT}: no Pinocchio Data (GBs), aba/crba not run")
        M = M_denoc
        planar = _planar(case)
        gim_reference = "planar closed form (mpmath)" if planar is not None else ""
        M_ref = None if planar is None else np.array(planar.gim(q).tolist(), dtype=float)
    gim_error = (
        None if M_ref is None else float(np.linalg.norm(M_denoc - M_ref) / np.linalg.norm(M_ref))
    )
    return M, gim_error, gim_reference


def _cholesky_ok(M: np.ndarray, notes: list[str]) -> bool:
    """Whether M is numerically positive definite (its Cholesky factor exists)."""
    try:
        scipy.linalg.cholesky(M, lower=True)
    except np.linalg.LinAlgError:
        notes.append("Cholesky of M failed: M is not numerically positive definite")
        return False
    return True


def _qdd_errors(
    methods: dict[str, Callable | None], q: np.ndarray, v: np.ndarray, tau: np.ndarray, exact
) -> dict[str, float | None]:
    """Each method's ‖q̈ − q̈_exact‖ / ‖q̈_exact‖; None for a method not run."""
    errors: dict[str, float | None] = {}
    for name, method in methods.items():
        if method is None:
            errors[name] = None
            continue
        a = np.asarray(method(q, v, tau), dtype=float)
        errors[name] = float(np.linalg.norm(a - exact) / np.linalg.norm(exact))
    return errors


def _simulated(
    case: StressCase, robot: Robot, q: np.ndarray, simulate: bool, notes: list[str]
) -> tuple[bool, str, float | None]:
    """(simulated, status, energy drift): the case simulated when asked and allowed."""
    if simulate and case.no_simulation:
        notes.append(f"not simulated: {case.no_simulation}")
        return False, "", None
    if not simulate:
        return False, "", None
    return (True, *simulate_case(case, robot, q))


def run_case(case: StressCase, *, seed: int = 0, simulate: bool = False) -> StressResult:
    """Run every check of the suite on ``case`` (see the module docstring)."""
    robot, q = case.build()
    nv = robot.nv
    rng = np.random.default_rng(seed)
    v, tau = rng.uniform(-1.0, 1.0, nv), rng.uniform(-10.0, 10.0, nv)
    dm = denoc_model(robot)
    g = tuple(case.gravity_m_s2)
    methods: dict[str, Callable | None] = dict.fromkeys(METHODS)
    methods["denoc"] = lambda q, v, tau: dm.forward_dynamics(q, v, tau, gravity=g)
    notes: list[str] = []
    ref_name, reference = _reference(case, robot)
    M_denoc = dm.gim(q)
    crba_gim = None
    if nv <= DATA_NV_LIMIT:
        pin_methods, crba_gim = _pinocchio_methods(robot, g)
        methods.update(pin_methods)
    M, gim_error, gim_reference = _gim_against_reference(case, q, M_denoc, crba_gim, notes)
    cholesky_ok = _cholesky_ok(M, notes)
    kappa = conditioning.condition_number(M) if cholesky_ok else math.inf
    estimators_ok = cholesky_ok and _estimators_finite(M)
    errors = _qdd_errors(methods, q, v, tau, reference(q, v, tau))
    bound = error_constant(nv) * kappa * EPS
    simulate, sim_status, drift = _simulated(case, robot, q, simulate, notes)
    within = all(
        e is not None and np.isfinite(e) and e <= bound for e in errors.values() if e is not None
    )
    passed = (
        cholesky_ok
        and estimators_ok
        and (gim_error is None or gim_error <= GIM_RTOL)
        and within
        and (
            not simulate
            or (sim_status == "completed" and drift is not None and drift <= ENERGY_DRIFT_LIMIT)
        )
    )
    if not within:
        notes.append("a q̈ error is above C·κ·eps")
    if kappa * EPS >= 1e-3:
        notes.append(
            "κ·eps ≥ 1e-3: float64 resolves neither κ nor q̈ by the bound (it is vacuous); "
            "the errors are still measured against mpmath"
        )
    return StressResult(
        case=case.name,
        family=case.family,
        nv=nv,
        kappa=float(kappa),
        delta=float(conditioning.diagonal_ratio(M)),
        cholesky_ok=cholesky_ok,
        gim_error=gim_error,
        gim_reference=gim_reference,
        errors=errors,
        bound=float(bound),
        reference=ref_name,
        estimators_finite=estimators_ok,
        sim_status=sim_status,
        sim_energy_drift=drift,
        passed=bool(passed),
        note="; ".join(notes),
    )


def simulate_case(case: StressCase, robot: Robot, q: np.ndarray) -> tuple[str, float | None]:
    """5 s under gravity from rest at q: (status, relative energy drift)."""
    from gimwatch.simulation.scene import parse_scene
    from gimwatch.simulation.simulate import Simulation

    table: dict = {
        "robot": "placeholder",
        "duration": SIMULATION_S,
        "sample": 0.05,
        "q": [float(x) for x in q],
        "effects": {"gravity": {"vector": list(case.gravity_m_s2)}},
    }
    if robot.nq != robot.nv:
        table["integrator"] = {"method": "RK4", "dt": 1e-3}
    else:
        table["integrator"] = {"method": "DOP853", "rtol": 1e-10, "atol": 1e-10}
    if robot.nv > DATA_NV_LIMIT:  # no Pinocchio Data: the O(n) DeNOC recursions
        table["dynamics"] = {"backend": "denoc"}
    scene = parse_scene(table, source=f"<stress {case.name}>")
    trajectory = Simulation(scene, robot=robot).run()
    return trajectory.status, trajectory.energy_drift()


def run_stress(
    names: Iterable[str] | None = None,
    *,
    quick: bool = False,
    simulate: bool = True,
    seed: int = 0,
    progress: Callable[[str], None] = lambda line: None,
) -> list[StressResult]:
    """Run the named cases (all, or the quick ones) and return their results in order."""
    selected = list(CASES) if names is None else list(names)
    for name in selected:
        if name not in CASES:
            raise InputError("the stress case", f"one of {', '.join(CASES)}", name)
    results = []
    for name in selected:
        case = CASES[name]
        if quick and not case.quick:
            continue
        progress(f"stress case {name}")
        results.append(run_case(case, seed=seed, simulate=simulate))
    return results


def _fmt(value: float | None) -> str:
    return "–" if value is None else f"{value:.2g}"


def stress_markdown(results: list[StressResult]) -> str:
    """The results as a Markdown table: κ, q̈ error per method, C·κ·eps, the other checks."""
    lines = [
        "| case | nv | κ | " + " | ".join(f"`{m}`" for m in METHODS) + " | C·κ·eps "
        "| DeNOC M err | sim drift | reference | ok |",
        "|---|---:|---:|" + "---:|" * len(METHODS) + "---:|---:|---:|---|---|",
    ]
    for r in results:
        drift = _fmt(r.sim_energy_drift) if r.sim_status in ("completed", "") else r.sim_status
        cells = [
            r.case,
            str(r.nv),
            f"{r.kappa:.2g}",
            *(_fmt(r.errors[m]) for m in METHODS),
            f"{r.bound:.2g}",
            _fmt(r.gim_error),
            drift or "–",
            r.reference,
            "yes" if r.passed else "**no**",
        ]
        lines.append("| " + " | ".join(cells) + " |")
    notes = [f"- `{r.case}`: {r.note}" for r in results if r.note]
    return "\n".join(lines + (["", *notes] if notes else []))
